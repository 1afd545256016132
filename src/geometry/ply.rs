//! Stanford PLY loading: ASCII, binary little-endian and binary big-endian, with the file and
//! the element (and, in ASCII, the line) in every error.
//!
//! Only the `vertex` element's `x`, `y`, `z` and the `face` element's `vertex_indices` (or
//! `vertex_index`) list are read; every other element and property is parsed and skipped.
//! Polygons are fan-triangulated; positions are kept in f64 until the mesh is rebased
//! ([`Mesh::from_file_parts`]). The header's counts are checked against the bytes that follow
//! it before anything is allocated, and the body must end exactly where the counts say: a
//! header that lies about its counts, in either direction, is an error, never a silently
//! shortened or padded mesh. An element declared twice, or declaring instances without
//! properties (they take no bytes, so nothing in the file bounds their count), is refused by
//! the header parser that the size precheck ([`ply_header_counts`]) and the loader share.

use super::{GeometryError, Mesh};
use std::path::Path;

mod body;

/// The longest header read before giving up on finding `end_header`.
const MAX_HEADER_BYTES: usize = 1 << 20;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    Little,
    Big,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(word: &str) -> Option<Scalar> {
        Some(match word {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar(Scalar, String),
    List(Scalar, Scalar, String),
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    /// 1-based header line of its `element` line.
    line: usize,
}

impl Element {
    /// The fewest bytes one instance takes in `format` (an ASCII value is at least one
    /// character and a separator).
    fn min_bytes(&self, format: Format) -> u64 {
        self.properties
            .iter()
            .map(|p| match (format, p) {
                (Format::Ascii, _) => 2,
                (_, Property::Scalar(s, _)) | (_, Property::List(s, _, _)) => s.size() as u64,
            })
            .sum()
    }
}

/// A PLY file's header: its format, elements and where the body starts.
#[derive(Clone, Debug)]
struct Header {
    format: Format,
    elements: Vec<Element>,
    body: usize,
    /// 1-based line number of the body's first line (for ASCII errors).
    body_line: usize,
}

impl Header {
    /// The element the header declares as `name`.
    fn element(&self, name: &str) -> Option<&Element> {
        self.elements.iter().find(|e| e.name == name)
    }
}

/// The vertex and face counts a PLY file's header declares, read without the body (to check a
/// file against a memory limit before loading it).
pub fn ply_header_counts(path: &Path) -> Result<(u64, u64), GeometryError> {
    use std::io::Read;
    let display = path.display().to_string();
    let io = GeometryError::io(path);
    let mut head = Vec::new();
    std::fs::File::open(path)
        .map_err(io)?
        .take(MAX_HEADER_BYTES as u64)
        .read_to_end(&mut head)
        .map_err(io)?;
    let h = parse_header(&head, &display)?;
    let count = |name: &str| h.element(name).map_or(0, |e| e.count);
    Ok((count("vertex"), count("face")))
}

impl Mesh {
    /// Loads a PLY file and validates it with [`Mesh::from_parts`]; see the module doc.
    /// Vertices used by no face are dropped (as [`Mesh::load_obj`] does); vertices are not
    /// welded (a PLY file shares them by index). The mesh is named by the file name.
    pub fn load_ply(path: &Path) -> Result<Mesh, GeometryError> {
        let bytes = std::fs::read(path).map_err(GeometryError::io(path))?;
        Mesh::ply_from_bytes(&bytes, path)
    }

    /// [`Mesh::load_ply`] on the file's bytes, already read; `path` names it.
    pub fn ply_from_bytes(bytes: &[u8], path: &Path) -> Result<Mesh, GeometryError> {
        let display = path.display().to_string();
        let bad = |m: String| GeometryError::invalid(&display, m);
        let h = parse_header(bytes, &display)?;
        let lay = layout(&h, &display)?;
        let (positions, triangles) = body::read(bytes, &h, &lay).map_err(bad)?;
        let (positions, origin) = super::rebase::centred_positions(&positions);
        Mesh::from_file_parts(path, positions, origin, triangles).map_err(|e| bad(e.to_string()))
    }
}

fn parse_header(bytes: &[u8], file: &str) -> Result<Header, GeometryError> {
    let bad = |m: String| GeometryError::invalid(file, m);
    if !(bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n")) {
        return Err(bad("not a PLY file: the first line is not `ply`".into()));
    }
    let mut lines = Vec::new();
    let mut start = 0;
    let mut body = None;
    while start < bytes.len().min(MAX_HEADER_BYTES) {
        let end = bytes[start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| start + i);
        let line = std::str::from_utf8(&bytes[start..end])
            .map_err(|_| bad(format!("header line {}: not text", lines.len() + 1)))?
            .trim_end_matches('\r');
        lines.push(line);
        start = end + 1;
        if line.trim() == "end_header" {
            body = Some(start.min(bytes.len()));
            break;
        }
    }
    let body = body.ok_or_else(|| bad("the header has no `end_header` line".into()))?;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for (i, line) in lines.iter().enumerate().skip(1) {
        let at = i + 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] | ["end_header"] => {}
            ["format", f, version] => {
                if *version != "1.0" {
                    return Err(bad(format!(
                        "header line {at}: format version `{version}`, not 1.0"
                    )));
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    other => {
                        return Err(bad(format!(
                            "header line {at}: unknown format `{other}` (ascii, \
                             binary_little_endian, binary_big_endian)"
                        )))
                    }
                });
            }
            ["element", name, count] => {
                let count = count.parse::<u64>().map_err(|_| {
                    bad(format!(
                        "header line {at}: element `{name}` count `{count}` is not a count"
                    ))
                })?;
                // A second `vertex` (or any) element would be read as data of the first's
                // kind and counted once: refused, here and in the size precheck alike.
                if let Some(first) = elements.iter().find(|e| e.name == *name) {
                    return Err(bad(format!(
                        "header line {at}: element `{name}` is declared again (first at header \
                         line {}); each element may be declared once",
                        first.line
                    )));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                    line: at,
                });
            }
            ["property", "list", c, t, name] => {
                let (Some(c), Some(t)) = (Scalar::parse(c), Scalar::parse(t)) else {
                    return Err(bad(format!(
                        "header line {at}: unknown property type in `{line}`"
                    )));
                };
                if !c.is_integer() {
                    return Err(bad(format!(
                        "header line {at}: a list's count type must be an integer"
                    )));
                }
                let e = elements.last_mut().ok_or_else(|| {
                    bad(format!("header line {at}: a property before any element"))
                })?;
                e.properties.push(Property::List(c, t, name.to_string()));
            }
            ["property", t, name] => {
                let t = Scalar::parse(t)
                    .ok_or_else(|| bad(format!("header line {at}: unknown property type `{t}`")))?;
                let e = elements.last_mut().ok_or_else(|| {
                    bad(format!("header line {at}: a property before any element"))
                })?;
                e.properties.push(Property::Scalar(t, name.to_string()));
            }
            _ => return Err(bad(format!("header line {at}: cannot read `{line}`"))),
        }
    }
    let format = format.ok_or_else(|| bad("the header has no `format` line".into()))?;
    // An instance without properties takes no bytes, so its count is bounded by nothing in the
    // file (a binary reader would loop over it up to 2⁶⁴ times), and ASCII cannot write one.
    if let Some(e) = elements
        .iter()
        .find(|e| e.properties.is_empty() && e.count > 0)
    {
        return Err(bad(format!(
            "header line {}: element `{}` declares {} instances but no properties (an instance \
             without properties holds no data)",
            e.line, e.name, e.count
        )));
    }
    Ok(Header {
        format,
        elements,
        body,
        body_line: lines.len() + 1,
    })
}

/// Where x, y, z and the face list sit among an element's properties.
struct Layout {
    xyz: [usize; 3],
    indices: usize,
    /// The face list's name (`vertex_indices` or `vertex_index`).
    indices_name: String,
}

fn layout(h: &Header, file: &str) -> Result<Layout, GeometryError> {
    let bad = |m: String| GeometryError::invalid(file, m);
    let vertex = h
        .element("vertex")
        .ok_or_else(|| bad("the header declares no `vertex` element".into()))?;
    let scalar = |name: &str| {
        vertex
            .properties
            .iter()
            .position(|p| matches!(p, Property::Scalar(_, n) if n == name))
            .ok_or_else(|| {
                bad(format!(
                    "the `vertex` element has no scalar property `{name}`"
                ))
            })
    };
    let xyz = [scalar("x")?, scalar("y")?, scalar("z")?];
    let face = h
        .element("face")
        .ok_or_else(|| bad("no faces: the header declares no `face` element".into()))?;
    let (indices, indices_name) = face
        .properties
        .iter()
        .enumerate()
        .find_map(|(i, p)| match p {
            Property::List(_, t, n)
                if t.is_integer() && (n == "vertex_indices" || n == "vertex_index") =>
            {
                Some((i, n.clone()))
            }
            _ => None,
        })
        .ok_or_else(|| {
            bad(
                "the `face` element has no integer list `vertex_indices` (or `vertex_index`)"
                    .into(),
            )
        })?;
    if vertex.count > u32::MAX as u64 {
        return Err(bad(format!(
            "{} vertices: more than 32-bit indices can address",
            vertex.count
        )));
    }
    Ok(Layout {
        xyz,
        indices,
        indices_name,
    })
}
