//! PLY (ours: file format support). A strict reader of ASCII, binary little- and big-endian
//! PLY with any scalar type, and a writer (header + little-endian bytes, or ASCII lines).
//!
//! Strict where the format is: the header is `ply`, `format ascii|binary_little_endian|
//! binary_big_endian 1.0`, then `comment`, `obj_info`, `element NAME COUNT`,
//! `property TYPE NAME` and `property list COUNT_TYPE ITEM_TYPE NAME` lines, and `end_header`.
//! ASCII data holds one element per line with exactly the values its properties declare
//! (blank lines are skipped; nothing but blank lines may follow the last element); binary data
//! holds exactly the bytes the header declares. Float values may be `nan` or `inf` (as trimesh
//! reads them) except the vertices' x, y and z; other properties' values are ignored (normals
//! with a non-finite component are dropped). Errors name the line (header and ASCII data) or
//! the element (binary) and what was expected, in plain words.

use std::io::{BufRead, Write};
use std::path::Path;

use glam::DVec3;

use crate::{FaceBuilder, Format, MeshIoError, Options, PointCloud, TriMesh};

/// A PLY scalar type. Every value of every type is exactly representable as an `f64`.
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
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
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
    fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }
    fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }
    /// Parse an ASCII token as this type (floats: digits, sign, `.` and exponent, or `nan`,
    /// `inf`, `infinity` in any case, as numpy and trimesh read them; x, y and z must then
    /// be finite, see [`read_record`]; `float` is parsed as `f32`, as a reader in `f32` would).
    fn parse_token(self, tok: &str) -> Option<f64> {
        fn int<T: std::str::FromStr + Into<f64>>(t: &str) -> Option<f64> {
            t.parse::<T>().ok().map(Into::into)
        }
        match self {
            Scalar::I8 => int::<i8>(tok),
            Scalar::U8 => int::<u8>(tok),
            Scalar::I16 => int::<i16>(tok),
            Scalar::U16 => int::<u16>(tok),
            Scalar::I32 => int::<i32>(tok),
            Scalar::U32 => int::<u32>(tok),
            Scalar::F32 | Scalar::F64 => {
                let numeric = |c: char| c.is_ascii_digit() || "+-.eE".contains(c);
                let word = tok.trim_start_matches(['+', '-']).to_ascii_lowercase();
                let special = ["nan", "inf", "infinity"].contains(&word.as_str());
                if !(special || tok.chars().all(numeric)) {
                    return None;
                }
                if self == Scalar::F32 {
                    tok.parse::<f32>().ok().map(f64::from)
                } else {
                    tok.parse::<f64>().ok()
                }
            }
        }
    }
    /// Decode `b` (`self.size()` bytes).
    fn decode(self, b: &[u8], big: bool) -> f64 {
        macro_rules! de {
            ($t:ty) => {{
                let a = b.try_into().expect("scalar size");
                (if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            }};
        }
        match self {
            Scalar::I8 => de!(i8),
            Scalar::U8 => de!(u8),
            Scalar::I16 => de!(i16),
            Scalar::U16 => de!(u16),
            Scalar::I32 => de!(i32),
            Scalar::U32 => de!(u32),
            Scalar::F32 => de!(f32),
            Scalar::F64 => de!(f64),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

struct Prop {
    name: String,
    kind: Kind,
}

struct Element {
    name: String,
    count: usize,
    props: Vec<Prop>,
}

impl Element {
    fn scalar(&self, name: &str) -> Option<usize> {
        self.props
            .iter()
            .position(|p| p.name == name && matches!(p.kind, Kind::Scalar(_)))
    }
    /// The properties, as the header declares them (for messages).
    fn describe(&self) -> String {
        let p: Vec<String> = self
            .props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => format!("{} {}", s.name(), p.name),
                Kind::List { count, item } => {
                    format!("list {} {} {}", count.name(), item.name(), p.name)
                }
            })
            .collect();
        p.join(", ")
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Binary { big: bool },
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Number of header lines (the ASCII data starts on line `lines + 1`).
    lines: usize,
}

/// Read the header up to and including the `end_header` line.
fn read_header<R: BufRead>(r: &mut R, path: &Path) -> Result<Header, MeshIoError> {
    let bad = |line: usize, what: String| {
        MeshIoError::not_a_mesh(path, Format::Ply, format!("header line {line}: {what}"))
    };
    let mut buf = Vec::new();
    let mut line_no = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        buf.clear();
        let n = r
            .read_until(b'\n', &mut buf)
            .map_err(|e| MeshIoError::io(path, e))?;
        if n == 0 {
            return Err(MeshIoError::Truncated {
                path: path.to_owned(),
                detail: format!("the header ends after {line_no} lines without end_header"),
            });
        }
        line_no += 1;
        let Ok(text) = std::str::from_utf8(&buf) else {
            return Err(bad(line_no, "not ASCII text".into()));
        };
        let toks: Vec<&str> = text.split_ascii_whitespace().collect();
        if line_no == 1 {
            if toks != ["ply"] {
                return Err(bad(1, format!("expected \"ply\", found {:?}", text.trim())));
            }
            continue;
        }
        let Some(&kw) = toks.first() else {
            return Err(bad(line_no, "empty line (remove it)".into()));
        };
        if kw != "format" && kw != "comment" && kw != "obj_info" && encoding.is_none() {
            return Err(bad(
                line_no,
                format!("expected the format line before {kw:?}"),
            ));
        }
        match kw {
            "format" => {
                if encoding.is_some() {
                    return Err(bad(line_no, "a second format line".into()));
                }
                encoding = Some(parse_format(&toks).map_err(|w| bad(line_no, w))?);
            }
            "comment" | "obj_info" => {}
            "element" => {
                let el = parse_element(&toks).map_err(|w| bad(line_no, w))?;
                if elements.iter().any(|e| e.name == el.name) {
                    return Err(bad(line_no, format!("a second element {:?}", el.name)));
                }
                elements.push(el);
            }
            "property" => {
                let Some(el) = elements.last_mut() else {
                    return Err(bad(line_no, "a property before any element".into()));
                };
                let p = parse_property(&toks).map_err(|w| bad(line_no, w))?;
                if el.props.iter().any(|q| q.name == p.name) {
                    return Err(bad(
                        line_no,
                        format!("element {} has a second property {:?}", el.name, p.name),
                    ));
                }
                el.props.push(p);
            }
            "end_header" if toks.len() == 1 => break,
            _ => {
                return Err(bad(
                    line_no,
                    format!(
                        "expected format, comment, obj_info, element, property or end_header, \
                         found {:?}",
                        text.trim()
                    ),
                ));
            }
        }
    }
    let Some(encoding) = encoding else {
        return Err(bad(line_no, "the header has no format line".into()));
    };
    Ok(Header {
        encoding,
        elements,
        lines: line_no,
    })
}

fn parse_format(toks: &[&str]) -> Result<Encoding, String> {
    let enc = match toks.get(1).copied() {
        Some("ascii") => Encoding::Ascii,
        Some("binary_little_endian") => Encoding::Binary { big: false },
        Some("binary_big_endian") => Encoding::Binary { big: true },
        _ => {
            return Err(format!(
                "expected 'format ascii|binary_little_endian|binary_big_endian 1.0', found {:?}",
                toks.join(" ")
            ));
        }
    };
    match &toks[2..] {
        ["1.0"] => Ok(enc),
        [v] => Err(format!(
            "PLY version {v} is not supported (only 1.0 exists)"
        )),
        _ => Err(format!(
            "expected 'format {} 1.0', found {:?}",
            toks[1],
            toks.join(" ")
        )),
    }
}

fn parse_element(toks: &[&str]) -> Result<Element, String> {
    let [_, name, count] = toks else {
        return Err(format!(
            "expected 'element NAME COUNT', found {:?}",
            toks.join(" ")
        ));
    };
    let count = count.parse::<usize>().map_err(|_| {
        format!("element {name}: the count {count:?} is not a non-negative integer")
    })?;
    Ok(Element {
        name: name.to_string(),
        count,
        props: Vec::new(),
    })
}

fn parse_property(toks: &[&str]) -> Result<Prop, String> {
    let ty = |t: &str| {
        Scalar::parse(t).ok_or_else(|| {
            format!(
                "unknown type {t:?}; PLY types are char, uchar, short, ushort, int, uint, \
                 float, double (or int8 ... float64)"
            )
        })
    };
    match toks {
        [_, "list", c, i, name] => {
            let count = ty(c)?;
            if count.is_float() {
                return Err(format!(
                    "list {name}: the count type {c} is not an integer type"
                ));
            }
            Ok(Prop {
                name: name.to_string(),
                kind: Kind::List {
                    count,
                    item: ty(i)?,
                },
            })
        }
        [_, t, name] if *t != "list" => Ok(Prop {
            name: name.to_string(),
            kind: Kind::Scalar(ty(t)?),
        }),
        _ => Err(format!(
            "expected 'property TYPE NAME' or 'property list COUNT_TYPE ITEM_TYPE NAME', found {:?}",
            toks.join(" ")
        )),
    }
}

/// Where the values of one property go.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Slot {
    Drop,
    Coord(usize),
    Indices,
}

/// One element instance as read: the coordinates `x y z nx ny nz` and the vertex indices.
#[derive(Default)]
struct Record {
    coords: [f64; 6],
    idx: Vec<i64>,
}

/// Why a value could not be read.
enum Fail {
    /// The ASCII line ended before this property.
    Missing,
    /// The binary data ended.
    Eof,
    /// The ASCII token is not a value of the property's type.
    Token(String, Scalar),
    /// A list count is negative.
    NegativeCount(f64),
    /// A NaN or infinite x, y or z.
    NonFinite(f64),
    Io(std::io::Error),
}

/// A source of typed values: the tokens of one ASCII line, or binary bytes.
trait Values {
    fn next(&mut self, t: Scalar) -> Result<f64, Fail>;
}

struct Tokens<'a>(std::str::SplitAsciiWhitespace<'a>);

impl Values for Tokens<'_> {
    fn next(&mut self, t: Scalar) -> Result<f64, Fail> {
        let tok = self.0.next().ok_or(Fail::Missing)?;
        t.parse_token(tok)
            .ok_or_else(|| Fail::Token(tok.to_string(), t))
    }
}

struct Bytes<'r, R> {
    r: &'r mut R,
    big: bool,
}

impl<R: BufRead> Values for Bytes<'_, R> {
    fn next(&mut self, t: Scalar) -> Result<f64, Fail> {
        let mut b = [0u8; 8];
        let b = &mut b[..t.size()];
        self.r.read_exact(b).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                Fail::Eof
            } else {
                Fail::Io(e)
            }
        })?;
        Ok(t.decode(b, self.big))
    }
}

/// Read one element instance; on failure, the index of the property and why.
fn read_record<V: Values>(
    v: &mut V,
    el: &Element,
    slots: &[Slot],
    rec: &mut Record,
) -> Result<(), (usize, Fail)> {
    rec.idx.clear();
    for (k, (p, &slot)) in el.props.iter().zip(slots).enumerate() {
        match p.kind {
            Kind::Scalar(t) => {
                let x = v.next(t).map_err(|f| (k, f))?;
                if let Slot::Coord(c) = slot {
                    if c < 3 && !x.is_finite() {
                        return Err((k, Fail::NonFinite(x)));
                    }
                    rec.coords[c] = x;
                }
            }
            Kind::List { count, item } => {
                let n = v.next(count).map_err(|f| (k, f))?;
                if n < 0.0 {
                    return Err((k, Fail::NegativeCount(n)));
                }
                for _ in 0..n as usize {
                    let x = v.next(item).map_err(|f| (k, f))?;
                    if slot == Slot::Indices {
                        rec.idx.push(x as i64); // an integer type: exact
                    }
                }
            }
        }
    }
    Ok(())
}

/// Reads the data of the elements in order, counting ASCII lines for the messages.
struct DataReader<'a, R> {
    r: &'a mut R,
    path: &'a Path,
    encoding: Encoding,
    line_no: usize,
    line: Vec<u8>,
}

impl<R: BufRead> DataReader<'_, R> {
    /// The next non-blank ASCII line (`None` at the end of the file).
    fn next_line(&mut self) -> Result<Option<&str>, MeshIoError> {
        loop {
            self.line.clear();
            let n = self
                .r
                .read_until(b'\n', &mut self.line)
                .map_err(|e| MeshIoError::io(self.path, e))?;
            if n == 0 {
                return Ok(None);
            }
            self.line_no += 1;
            let Ok(s) = std::str::from_utf8(&self.line) else {
                return Err(self.bad(format!("line {}: not ASCII text", self.line_no)));
            };
            if !s.trim_ascii().is_empty() {
                return Ok(Some(std::str::from_utf8(&self.line).unwrap_or_default()));
            }
        }
    }

    fn bad(&self, what: String) -> MeshIoError {
        MeshIoError::not_a_mesh(self.path, Format::Ply, what)
    }

    /// Read every instance of `el`, passing each to `each`.
    fn element(
        &mut self,
        el: &Element,
        slots: &[Slot],
        mut each: impl FnMut(&Record) -> Result<(), MeshIoError>,
    ) -> Result<(), MeshIoError> {
        let mut rec = Record::default();
        for i in 0..el.count {
            let r = match self.encoding {
                Encoding::Ascii => {
                    let Some(line) = self.next_line()? else {
                        return Err(MeshIoError::Truncated {
                            path: self.path.to_owned(),
                            detail: format!(
                                "the header declares {} {} elements, the data ends after {i}",
                                el.count, el.name
                            ),
                        });
                    };
                    let mut toks = Tokens(line.split_ascii_whitespace());
                    let r = read_record(&mut toks, el, slots, &mut rec);
                    let extra = toks.0.count();
                    if r.is_ok() && extra > 0 {
                        let line = line.trim().to_string();
                        return Err(self.bad(format!(
                            "line {}: {} {i} has {extra} value(s) more than the header declares \
                             ({}); the line is {line:?}",
                            self.line_no,
                            el.name,
                            el.describe(),
                        )));
                    }
                    r
                }
                Encoding::Binary { big } => {
                    read_record(&mut Bytes { r: self.r, big }, el, slots, &mut rec)
                }
            };
            if let Err((k, fail)) = r {
                return Err(self.fail(el, i, k, fail));
            }
            each(&rec)?;
        }
        Ok(())
    }

    /// The error for property `k` of instance `i` of `el`.
    fn fail(&self, el: &Element, i: usize, k: usize, fail: Fail) -> MeshIoError {
        let p = &el.props[k];
        let at = match self.encoding {
            Encoding::Ascii => format!("line {}: {} {i}", self.line_no, el.name),
            Encoding::Binary { .. } => format!("{} {i}", el.name),
        };
        match fail {
            Fail::Missing => self.bad(format!(
                "{at} has too few values: property {} is missing (the header declares {})",
                p.name,
                el.describe()
            )),
            Fail::Token(t, ty) => self.bad(format!(
                "{at}, property {}: {t:?} is not a valid {} value",
                p.name,
                ty.name()
            )),
            Fail::NonFinite(x) => self.bad(format!(
                "{at}, property {}: {x} is not a finite coordinate; x, y and z must be finite \
                 numbers (other properties may be nan or inf)",
                p.name
            )),
            Fail::NegativeCount(n) => self.bad(format!(
                "{at}, property {}: list count {n} is negative",
                p.name
            )),
            Fail::Eof => MeshIoError::Truncated {
                path: self.path.to_owned(),
                detail: format!(
                    "the data ends inside {} {i} of the {} the header declares",
                    el.name, el.count
                ),
            },
            Fail::Io(e) => MeshIoError::io(self.path, e),
        }
    }

    /// Check that nothing but blank lines (ASCII) or nothing at all (binary) follows.
    fn finish(&mut self) -> Result<(), MeshIoError> {
        match self.encoding {
            Encoding::Ascii => match self.next_line()? {
                None => Ok(()),
                Some(l) => {
                    let l = l.trim().to_string();
                    Err(self.bad(format!(
                        "line {}: data after the last element ({l:?}); the header's element \
                         counts do not match the data",
                        self.line_no
                    )))
                }
            },
            Encoding::Binary { .. } => {
                let mut rest = Vec::new();
                self.r
                    .read_to_end(&mut rest)
                    .map_err(|e| MeshIoError::io(self.path, e))?;
                if rest.is_empty() {
                    Ok(())
                } else {
                    Err(self.bad(format!(
                        "{} bytes after the last element; the header's element counts or types \
                         do not match the data",
                        rest.len()
                    )))
                }
            }
        }
    }
}

fn is_index_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

/// Read the `vertex` element (and the `face` element when `want_faces`); every other element
/// is read and dropped.
pub(crate) fn read_points_and_faces<R: BufRead>(
    reader: &mut R,
    path: &Path,
    want_faces: bool,
) -> Result<(PointCloud, Option<FaceBuilder>), MeshIoError> {
    let not_ply = |what: String| MeshIoError::not_a_mesh(path, Format::Ply, what);
    // Cheap magic check, so that a non-PLY file gets a clear message.
    let head = reader.fill_buf().map_err(|e| MeshIoError::io(path, e))?;
    if !head.starts_with(b"ply") {
        let shown: String = String::from_utf8_lossy(&head[..head.len().min(16)])
            .escape_debug()
            .collect();
        return Err(not_ply(format!(
            "the file does not start with \"ply\" (starts with \"{shown}\")"
        )));
    }
    let h = read_header(reader, path)?;
    let Some(vi) = h.elements.iter().position(|e| e.name == "vertex") else {
        return Err(not_ply("the header has no vertex element".into()));
    };
    let vert = &h.elements[vi];
    for c in ["x", "y", "z"] {
        if vert.scalar(c).is_none() {
            return Err(not_ply(format!(
                "the vertex element has no scalar property {c}"
            )));
        }
    }
    let with_normals = ["nx", "ny", "nz"].iter().all(|c| vert.scalar(c).is_some());
    let fi = h.elements.iter().position(|e| e.name == "face");
    let fi = fi.filter(|_| want_faces);
    let index_list = match fi {
        None => None,
        Some(fi) => Some(face_index_list(&h.elements[fi], fi < vi).map_err(not_ply)?),
    };
    let slots_of = |e: usize, el: &Element| -> Vec<Slot> {
        el.props
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let coord = ["x", "y", "z", "nx", "ny", "nz"]
                    .iter()
                    .position(|&c| c == p.name);
                match coord {
                    Some(c) if e == vi && matches!(p.kind, Kind::Scalar(_)) => Slot::Coord(c),
                    _ if Some(e) == fi && Some(k) == index_list => Slot::Indices,
                    _ => Slot::Drop,
                }
            })
            .collect()
    };
    let mut data = DataReader {
        r: reader,
        path,
        encoding: h.encoding,
        line_no: h.lines,
        line: Vec::new(),
    };
    let mut points = Vec::with_capacity(vert.count.min(1 << 20));
    let mut normals = Vec::new();
    let mut faces = fi.map(|_| FaceBuilder::default());
    for (e, el) in h.elements.iter().enumerate() {
        let slots = slots_of(e, el);
        if e == vi {
            data.element(el, &slots, |r| {
                let c = r.coords;
                points.push(DVec3::new(c[0], c[1], c[2]));
                if with_normals {
                    normals.push(DVec3::new(c[3], c[4], c[5]));
                }
                Ok(())
            })?;
        } else if let (true, Some(fb)) = (Some(e) == fi, faces.as_mut()) {
            let nv = vert.count;
            data.element(el, &slots, |r| {
                fb.push_polygon(&r.idx, nv)
                    .map_err(|source| MeshIoError::Invalid {
                        path: path.to_owned(),
                        source,
                    })
            })?;
        } else {
            data.element(el, &slots, |_| Ok(()))?;
        }
    }
    data.finish()?;
    crate::check_vertex_coords(path, &points)?;
    // Normals with a NaN or infinite component are ignored (estimated downstream), as the
    // values of every other non-coordinate property are.
    let normals_ok = normals.iter().all(|n| n.is_finite());
    let cloud = PointCloud {
        points,
        normals: (with_normals && normals_ok).then_some(normals),
    };
    Ok((cloud, faces))
}

/// The index of the face element's vertex index list (`vertex_indices` or `vertex_index`).
fn face_index_list(face: &Element, before_vertices: bool) -> Result<usize, String> {
    if before_vertices {
        return Err(
            "the face element comes before the vertex element; write vertices first".into(),
        );
    }
    let k = face
        .props
        .iter()
        .position(|p| is_index_list(&p.name) && matches!(p.kind, Kind::List { .. }))
        .ok_or("the face element has no list property vertex_indices or vertex_index")?;
    if let Kind::List { item, .. } = face.props[k].kind
        && item.is_float()
    {
        return Err(format!(
            "the face list {} has {} items; vertex indices must be an integer type",
            face.props[k].name,
            item.name()
        ));
    }
    Ok(k)
}

pub(crate) fn read<R: BufRead>(reader: &mut R, path: &Path) -> Result<TriMesh, MeshIoError> {
    let (cloud, faces) = read_points_and_faces(reader, path, true)?;
    Ok(TriMesh {
        vertices: cloud.points,
        triangles: faces.map(|f| f.triangles).unwrap_or_default(),
    })
}

pub(crate) fn write<W: Write>(w: &mut W, mesh: &TriMesh, o: Options) -> std::io::Result<()> {
    let ty = if o.double { "double" } else { "float" };
    let enc = if o.binary {
        "binary_little_endian"
    } else {
        "ascii"
    };
    write!(
        w,
        "ply\nformat {enc} 1.0\ncomment written by meshio\nelement vertex {}\n\
         property {ty} x\nproperty {ty} y\nproperty {ty} z\nelement face {}\n\
         property list uchar uint vertex_indices\nend_header\n",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    if o.binary {
        let mut buf = Vec::with_capacity(mesh.vertices.len() * 24);
        for v in &mesh.vertices {
            for c in v.to_array() {
                if o.double {
                    buf.extend_from_slice(&c.to_le_bytes());
                } else {
                    buf.extend_from_slice(&(c as f32).to_le_bytes());
                }
            }
        }
        w.write_all(&buf)?;
        buf.clear();
        buf.reserve(mesh.triangles.len() * 13);
        for t in &mesh.triangles {
            buf.push(3);
            for i in t {
                buf.extend_from_slice(&i.to_le_bytes());
            }
        }
        w.write_all(&buf)?;
    } else {
        crate::write_text_body(w, mesh, o.double, ("", "3 ", 0))?;
    }
    Ok(())
}
