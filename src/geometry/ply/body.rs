//! A PLY file's body: its element instances read one after another (ASCII lines or binary
//! records), the vertices' positions and the fan-triangulated faces kept, every error naming
//! the element, the instance and where it sits (line or byte). A body that does not read with
//! the header's `vertex` count but does with the count its length implies is reported with both.

use super::{Element, Format, Header, Layout, Property, Scalar};
use glam::DVec3;

/// The values of one element instance: scalars as f64, lists as their items (as f64, exact for
/// every integer type of PLY).
type Values = Vec<Vec<f64>>;

/// Reads the body's element instances one after another.
trait Body {
    /// Reads the next instance of `e` (number `k`) into `out` (one entry per property, reused
    /// from instance to instance), or the error naming it.
    fn next(&mut self, e: &Element, k: u64, out: &mut Values) -> Result<(), String>;
    /// Where the instance last read starts: `line N` (ASCII) or `byte N` (binary, in the file).
    fn place(&self) -> String;
    /// An error if anything but whitespace (ASCII) or nothing (binary) is left.
    fn finish(&mut self) -> Result<(), String>;
}

struct Ascii<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    first_line: usize,
    /// 1-based line of the instance last read.
    at: usize,
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
        self.at = at;
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
            let more = 1 + words.count();
            return Err(format!(
                "line {at} ({} element {k}): {more} more value{} than the header's properties \
                 take (from `{extra}`)",
                e.name,
                if more == 1 { "" } else { "s" }
            ));
        }
        Ok(())
    }

    fn place(&self) -> String {
        format!("line {}", self.at)
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
    /// Where the instance last read starts, in the body.
    start: usize,
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
        self.start = self.at;
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
                            "{} element {k} (byte {}): list `{name}` has length {n}",
                            e.name,
                            base + self.start
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

    fn place(&self) -> String {
        format!("byte {}", self.base + self.start)
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

/// The positions (as the file holds them, f64) and fan-triangulated faces of a PLY body, or
/// the error; when the body reads whole with another `vertex` count, the error says so.
pub(super) fn read(
    bytes: &[u8],
    h: &Header,
    lay: &Layout,
) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), String> {
    check_sizes(bytes, h)?;
    read_body(bytes, h, lay).map_err(|e| match other_vertex_count(bytes, h, lay) {
        Some((declared, holds)) => format!(
            "the header declares {} `vertex` elements (header line {}), but the body holds \
             {holds}: read with {holds} the file is whole (with {}: {e})",
            declared.count, declared.line, declared.count
        ),
        None => e,
    })
}

/// Every count against the bytes that follow the header, before anything is allocated from
/// it: an instance takes at least one byte (binary) or two (ASCII) a property, and an element
/// without properties has no instances ([`super::parse_header`]), so every loop of the reader
/// is bounded by the file's bytes.
fn check_sizes(bytes: &[u8], h: &Header) -> Result<(), String> {
    let mut left = (bytes.len() - h.body) as u64;
    for e in &h.elements {
        let need = e.count.saturating_mul(e.min_bytes(h.format));
        if need > left {
            return Err(format!(
                "the header declares {} `{}` elements, at least {need} bytes, but only {left} \
                 bytes follow (its counts are wrong, or the file is truncated)",
                e.count, e.name
            ));
        }
        left -= need;
    }
    Ok(())
}

fn read_body(
    bytes: &[u8],
    h: &Header,
    lay: &Layout,
) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), String> {
    let body = &bytes[h.body..];
    let mut reader: Box<dyn Body> = match h.format {
        Format::Ascii => {
            let text = std::str::from_utf8(body).map_err(|e| {
                format!(
                    "the ASCII body is not text (byte {})",
                    h.body + e.valid_up_to()
                )
            })?;
            Box::new(Ascii {
                lines: text.lines().enumerate(),
                first_line: h.body_line,
                at: h.body_line,
            })
        }
        f => Box::new(Binary {
            bytes: body,
            at: 0,
            big: f == Format::Big,
            base: h.body,
            start: 0,
        }),
    };
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut values = Values::new();
    let vertex_count = h.element("vertex").map_or(0, |e| e.count);
    for e in &h.elements {
        let is_vertex = e.name == "vertex";
        let is_face = e.name == "face";
        // Counts checked against the bytes (`check_sizes`), so these reservations are bounded
        // by the file.
        if is_vertex {
            positions.reserve(e.count as usize);
        } else if is_face {
            triangles.reserve(e.count as usize);
        }
        for k in 0..e.count {
            reader.next(e, k, &mut values)?;
            let v = &values;
            if is_vertex {
                let p = DVec3::from_array(lay.xyz.map(|i| v[i][0]));
                // A value finite in f64 but not as the f32 a mesh holds is refused here, with
                // its element (rebasing cannot bring it back: see `Mesh::from_file_parts`).
                if !p.as_vec3().is_finite() {
                    return Err(format!(
                        "vertex element {k} ({}): non-finite coordinate {} (as f32)",
                        reader.place(),
                        p.as_vec3()
                    ));
                }
                positions.push(p);
            } else if is_face {
                let list = &v[lay.indices];
                let name = &lay.indices_name;
                if list.len() < 3 {
                    return Err(format!(
                        "face element {k} of {} ({}): its `{name}` lists {} vertex indices, a \
                         face needs at least 3",
                        e.count,
                        reader.place(),
                        list.len()
                    ));
                }
                let mut idx = [0u32; 3];
                for (j, &i) in list.iter().enumerate() {
                    if !(i >= 0.0 && i < vertex_count as f64 && i.fract() == 0.0) {
                        return Err(format!(
                            "face element {k} of {} ({}): vertex index {i} (item {j} of its \
                             `{name}`) out of range: the header declares {vertex_count} \
                             vertices, indices from 0",
                            e.count,
                            reader.place()
                        ));
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
    reader.finish()?;
    Ok((positions, triangles))
}

/// When the body does not read with the header's `vertex` count: the count its length implies,
/// if the body reads whole with it (the header's `vertex` element, and that count). ASCII: one
/// line an instance, so the count is the header's plus the lines the body has over the
/// instances declared. Binary: the count whose fixed-size vertex records, with every other
/// element's records (faces taken as triangles), fill the body exactly. Only on the error path.
fn other_vertex_count<'h>(bytes: &[u8], h: &'h Header, lay: &Layout) -> Option<(&'h Element, u64)> {
    let (iv, vertex) = h
        .elements
        .iter()
        .enumerate()
        .find(|(_, e)| e.name == "vertex")?;
    let body = &bytes[h.body..];
    let holds: i128 = match h.format {
        Format::Ascii => {
            let lines = std::str::from_utf8(body)
                .ok()?
                .lines()
                .filter(|l| !l.trim().is_empty())
                .count() as i128;
            let declared: i128 = h.elements.iter().map(|e| e.count as i128).sum();
            vertex.count as i128 + lines - declared
        }
        Format::Little | Format::Big => {
            // Bytes of one instance with fixed-size records (a face's lists of 3 items).
            let record = |e: &Element| -> Option<i128> {
                e.properties
                    .iter()
                    .map(|p| match p {
                        Property::Scalar(s, _) => Some(s.size() as i128),
                        Property::List(c, t, _) if e.name == "face" => {
                            Some((c.size() + 3 * t.size()) as i128)
                        }
                        Property::List(..) => None,
                    })
                    .sum()
            };
            let size = record(vertex).filter(|&s| s > 0)?;
            let mut rest = body.len() as i128;
            for (i, e) in h.elements.iter().enumerate() {
                if i != iv {
                    rest -= record(e)? * e.count as i128;
                }
            }
            if rest < 0 || rest % size != 0 {
                return None;
            }
            rest / size
        }
    };
    let holds = u64::try_from(holds).ok().filter(|&n| n != vertex.count)?;
    let mut other = h.clone();
    other.elements[iv].count = holds;
    if holds > u32::MAX as u64 || check_sizes(bytes, &other).is_err() {
        return None;
    }
    read_body(bytes, &other, lay).ok()?;
    Some((vertex, holds))
}
