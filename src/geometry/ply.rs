//! Stanford PLY loading: ASCII, binary little-endian and binary big-endian, with the file and
//! the element (and, in ASCII, the line) in every error.
//!
//! Only the `vertex` element's `x`, `y`, `z` and the `face` element's `vertex_indices` (or
//! `vertex_index`) list are read; every other element and property is parsed and skipped.
//! Polygons are fan-triangulated. The header's counts are checked against the bytes that follow
//! it before anything is allocated, and the body must end exactly where the counts say: a
//! header that lies about its counts, in either direction, is an error, never a silently
//! shortened or padded mesh.

use super::mesh::PartsError;
use super::{GeometryError, Mesh};
use glam::Vec3;
use std::path::Path;

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

/// The vertex and face counts a PLY file's header declares, read without the body (to check a
/// file against a memory limit before loading it).
pub fn ply_header_counts(path: &Path) -> Result<(u64, u64), GeometryError> {
    use std::io::Read;
    let display = path.display().to_string();
    let io = |source| GeometryError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut head = Vec::new();
    std::fs::File::open(path)
        .map_err(io)?
        .take(MAX_HEADER_BYTES as u64)
        .read_to_end(&mut head)
        .map_err(io)?;
    let h = parse_header(&head, &display)?;
    let count = |name: &str| {
        h.elements
            .iter()
            .find(|e| e.name == name)
            .map_or(0, |e| e.count)
    };
    Ok((count("vertex"), count("face")))
}

impl Mesh {
    /// Loads a PLY file and validates it with [`Mesh::from_parts`]; see the module doc.
    /// Vertices used by no face are dropped (as [`Mesh::load_obj`] does); vertices are not
    /// welded (a PLY file shares them by index). The mesh is named by the file name.
    pub fn load_ply(path: &Path) -> Result<Mesh, GeometryError> {
        let bytes = std::fs::read(path).map_err(|source| GeometryError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Mesh::ply_from_bytes(&bytes, path)
    }

    /// [`Mesh::load_ply`] on the file's bytes, already read; `path` names it.
    pub fn ply_from_bytes(bytes: &[u8], path: &Path) -> Result<Mesh, GeometryError> {
        let display = path.display().to_string();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| display.clone());
        let (positions, triangles) = parse(bytes, &display)?;
        let (positions, triangles) = drop_unused(positions, triangles);
        Mesh::try_from_parts(&name, positions, triangles)
            .map_err(|e: PartsError| GeometryError::invalid(&display, e.to_string()))
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
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
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
}

fn layout(h: &Header, file: &str) -> Result<Layout, GeometryError> {
    let bad = |m: String| GeometryError::invalid(file, m);
    let vertex = h
        .elements
        .iter()
        .find(|e| e.name == "vertex")
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
        .elements
        .iter()
        .find(|e| e.name == "face")
        .ok_or_else(|| bad("no faces: the header declares no `face` element".into()))?;
    let indices = face
        .properties
        .iter()
        .position(|p| {
            matches!(p, Property::List(_, t, n)
                if t.is_integer() && (n == "vertex_indices" || n == "vertex_index"))
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
    Ok(Layout { xyz, indices })
}

/// The values of one element instance: scalars as f64, lists as their items (as f64, exact for
/// every integer type of PLY).
type Values = Vec<Vec<f64>>;

/// Reads the body's element instances one after another.
trait Body {
    /// Reads the next instance of `e` (number `k`) into `out` (one entry per property, reused
    /// from instance to instance), or the error naming it.
    fn next(&mut self, e: &Element, k: u64, out: &mut Values) -> Result<(), String>;
    /// An error if anything but whitespace (ASCII) or nothing (binary) is left.
    fn finish(&mut self) -> Result<(), String>;
}

struct Ascii<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    first_line: usize,
}

impl Body for Ascii<'_> {
    fn next(&mut self, e: &Element, k: u64, out: &mut Values) -> Result<(), String> {
        let (i, line) = loop {
            match self.lines.next() {
                Some((_, l)) if l.trim().is_empty() => continue,
                Some(x) => break x,
                None => {
                    return Err(format!(
                        "truncated: the file ends before {} element {k} of {} the header declares",
                        e.name, e.count
                    ))
                }
            }
        };
        let at = self.first_line + i;
        let mut words = line.split_whitespace();
        let mut word = |what: &str| {
            words.next().ok_or_else(|| {
                format!(
                    "line {at} ({} element {k}): too few values, no {what}",
                    e.name
                )
            })
        };
        out.resize_with(e.properties.len(), Vec::new);
        for (slot, p) in out.iter_mut().zip(&e.properties) {
            slot.clear();
            let num = |w: &str, name: &str| {
                w.parse::<f64>().map_err(|_| {
                    format!(
                        "line {at} ({} element {k}): `{w}` is not a number ({name})",
                        e.name
                    )
                })
            };
            match p {
                Property::Scalar(_, name) => slot.push(num(word(name)?, name)?),
                Property::List(_, _, name) => {
                    let w = word(name)?;
                    let n = w.parse::<u32>().map_err(|_| {
                        format!(
                            "line {at} ({} element {k}): list length `{w}` of `{name}`",
                            e.name
                        )
                    })?;
                    for _ in 0..n {
                        slot.push(num(word(name)?, name)?);
                    }
                }
            }
        }
        if let Some(extra) = words.next() {
            return Err(format!(
                "line {at} ({} element {k}): more values than the header's properties (`{extra}`)",
                e.name
            ));
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<(), String> {
        match self.lines.find(|(_, l)| !l.trim().is_empty()) {
            Some((i, _)) => Err(format!(
                "line {}: data after the last element the header declares (its counts are wrong)",
                self.first_line + i
            )),
            None => Ok(()),
        }
    }
}

struct Binary<'a> {
    bytes: &'a [u8],
    at: usize,
    big: bool,
    /// The body's offset in the file (for the byte offsets of errors).
    base: usize,
}

impl Binary<'_> {
    fn read(&mut self, s: Scalar) -> Option<f64> {
        let n = s.size();
        let b = self.bytes.get(self.at..self.at + n)?;
        self.at += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(b);
        if self.big {
            a[..n].reverse();
        }
        Some(match s {
            Scalar::I8 => a[0] as i8 as f64,
            Scalar::U8 => a[0] as f64,
            Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(a),
        })
    }
}

impl Body for Binary<'_> {
    fn next(&mut self, e: &Element, k: u64, out: &mut Values) -> Result<(), String> {
        let base = self.base;
        let truncated = |at: usize| {
            format!(
                "truncated: {} element {k} of {} the header declares runs past the file's end \
                 (byte {})",
                e.name,
                e.count,
                base + at
            )
        };
        out.resize_with(e.properties.len(), Vec::new);
        for (slot, p) in out.iter_mut().zip(&e.properties) {
            slot.clear();
            match p {
                Property::Scalar(s, _) => {
                    slot.push(self.read(*s).ok_or_else(|| truncated(self.at))?)
                }
                Property::List(c, t, name) => {
                    let n = self.read(*c).ok_or_else(|| truncated(self.at))?;
                    if n < 0.0 {
                        return Err(format!(
                            "{} element {k}: list `{name}` has length {n}",
                            e.name
                        ));
                    }
                    let n = n as usize;
                    if n.saturating_mul(t.size()) > self.bytes.len() - self.at {
                        return Err(truncated(self.at));
                    }
                    for _ in 0..n {
                        slot.push(self.read(*t).ok_or_else(|| truncated(self.at))?);
                    }
                }
            }
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<(), String> {
        let left = self.bytes.len() - self.at;
        if left > 0 {
            return Err(format!(
                "{left} bytes after the last element the header declares (its counts are wrong)"
            ));
        }
        Ok(())
    }
}

/// The positions and fan-triangulated faces of a PLY file's bytes.
fn parse(bytes: &[u8], file: &str) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), GeometryError> {
    let bad = |m: String| GeometryError::invalid(file, m);
    let h = parse_header(bytes, file)?;
    let lay = layout(&h, file)?;
    // Every count against the bytes left, before anything is allocated from it.
    let mut left = (bytes.len() - h.body) as u64;
    for e in &h.elements {
        let need = e.count.saturating_mul(e.min_bytes(h.format));
        if need > left {
            return Err(bad(format!(
                "the header declares {} `{}` elements, at least {need} bytes, but only {left} \
                 bytes follow (its counts are wrong, or the file is truncated)",
                e.count, e.name
            )));
        }
        left -= need;
    }
    let body = &bytes[h.body..];
    let text;
    let mut reader: Box<dyn Body> = match h.format {
        Format::Ascii => {
            text = std::str::from_utf8(body).map_err(|e| {
                bad(format!(
                    "the ASCII body is not text (byte {})",
                    h.body + e.valid_up_to()
                ))
            })?;
            Box::new(Ascii {
                lines: text.lines().enumerate(),
                first_line: h.body_line,
            })
        }
        f => Box::new(Binary {
            bytes: body,
            at: 0,
            big: f == Format::Big,
            base: h.body,
        }),
    };
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut values = Values::new();
    let vertex_count = h
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map_or(0, |e| e.count);
    for e in &h.elements {
        let is_vertex = e.name == "vertex";
        let is_face = e.name == "face";
        // Counts checked against the bytes above, so these reservations are bounded by the file.
        if is_vertex {
            positions.reserve(e.count as usize);
        } else if is_face {
            triangles.reserve(e.count as usize);
        }
        for k in 0..e.count {
            reader.next(e, k, &mut values).map_err(bad)?;
            let v = &values;
            if is_vertex {
                let p = Vec3::from_array(lay.xyz.map(|i| v[i][0] as f32));
                if !p.is_finite() {
                    return Err(bad(format!(
                        "vertex element {k}: non-finite coordinate {p} (as f32)"
                    )));
                }
                positions.push(p);
            } else if is_face {
                let list = &v[lay.indices];
                if list.len() < 3 {
                    return Err(bad(format!(
                        "face element {k}: {} vertex indices, a face needs at least 3",
                        list.len()
                    )));
                }
                let mut idx = [0u32; 3];
                for (j, &i) in list.iter().enumerate() {
                    if !(i >= 0.0 && i < vertex_count as f64 && i.fract() == 0.0) {
                        return Err(bad(format!(
                            "face element {k}: vertex index {i} out of range ({vertex_count} \
                             vertices, indices from 0)"
                        )));
                    }
                    let i = i as u32;
                    match j {
                        0 => idx[0] = i,
                        1 => idx[2] = i,
                        _ => {
                            idx[1] = idx[2];
                            idx[2] = i;
                            triangles.push(idx);
                        }
                    }
                }
            }
        }
    }
    reader.finish().map_err(bad)?;
    Ok((positions, triangles))
}

/// Keeps only the vertices some triangle uses, in their order, and renumbers the triangles.
fn drop_unused(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut map = vec![u32::MAX; positions.len()];
    for t in &triangles {
        for &i in t {
            map[i as usize] = 0;
        }
    }
    let mut kept = Vec::new();
    for (i, m) in map.iter_mut().enumerate() {
        if *m == 0 {
            *m = kept.len() as u32;
            kept.push(positions[i]);
        }
    }
    let triangles = triangles
        .into_iter()
        .map(|t| t.map(|i| map[i as usize]))
        .collect();
    (kept, triangles)
}
