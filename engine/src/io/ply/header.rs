//! PLY header: encoding, elements and their typed properties.
//!
//! Input: the file's bytes. Output: a [`Header`] and the byte offset where the body
//! starts. Cost: O(header length). Reference: Greg Turk, "The PLY Polygon File Format".

/// How the body is encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Encoding {
    /// Whitespace-separated numbers, one element record per line.
    Ascii,
    /// Packed little-endian values.
    BinaryLittleEndian,
    /// Packed big-endian values.
    BinaryBigEndian,
}

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scalar {
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
    /// Parses a type name, old (`uchar`) or sized (`uint8`) style.
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    /// Size in bytes in the binary encodings.
    pub(crate) fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    /// Whether values of this type are integers.
    pub(crate) fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

/// The type of a property: one scalar, or a list with its own count and item types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PropertyType {
    /// A single value.
    Scalar(Scalar),
    /// A length (of integer type `count`) followed by that many `item`s.
    List {
        /// Type of the length.
        count: Scalar,
        /// Type of each item.
        item: Scalar,
    },
}

/// A named property of an element.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Property {
    pub(crate) name: String,
    pub(crate) ty: PropertyType,
}

/// An element declaration: `count` records, each holding every property in order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Element {
    pub(crate) name: String,
    pub(crate) count: usize,
    pub(crate) properties: Vec<Property>,
    /// 1-based header line of the `element` declaration.
    pub(crate) line: usize,
}

impl Element {
    /// Index of the first property called `name`.
    pub(crate) fn property(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|p| p.name == name)
    }

    /// A lower bound on the bytes one record takes, used to bound allocations by the
    /// file size (an element may declare far more records than the file holds).
    pub(crate) fn min_record_bytes(&self, encoding: Encoding) -> usize {
        self.properties
            .iter()
            .map(|p| match (encoding, p.ty) {
                // One character and one separator per value (or list length).
                (Encoding::Ascii, _) => 2,
                (_, PropertyType::Scalar(s)) => s.size(),
                (_, PropertyType::List { count, .. }) => count.size(),
            })
            .sum()
    }
}

/// A parsed header.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Header {
    pub(crate) encoding: Encoding,
    pub(crate) elements: Vec<Element>,
    /// Byte offset of the first body byte (just after the `end_header` line break).
    pub(crate) body_start: usize,
    /// 1-based line of `end_header`.
    pub(crate) end_line: usize,
}

impl Header {
    /// Index of the first element called `name`.
    pub(crate) fn element(&self, name: &str) -> Option<usize> {
        self.elements.iter().position(|e| e.name == name)
    }
}

/// A header problem: 1-based line and what is wrong.
pub(crate) type HeaderError = (usize, String);

/// Parses the header at the start of `data`.
pub(crate) fn parse_header(data: &[u8]) -> Result<Header, HeaderError> {
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0;
    let mut line_no = 0;
    while pos < data.len() {
        line_no += 1;
        let end = data[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(data.len(), |i| pos + i);
        let raw = &data[pos..end];
        pos = (end + 1).min(data.len());
        let Ok(text) = std::str::from_utf8(raw) else {
            let what = if line_no == 1 {
                "not a PLY file (the first line must be `ply`)"
            } else {
                "header line is not text (missing `end_header`?)"
            };
            return Err((line_no, what.to_owned()));
        };
        let words: Vec<&str> = text.split_ascii_whitespace().collect();
        if line_no == 1 {
            if words != ["ply"] {
                return Err((
                    line_no,
                    "not a PLY file (the first line must be `ply`)".to_owned(),
                ));
            }
            continue;
        }
        let Some(&keyword) = words.first() else {
            continue; // tolerate blank lines
        };
        match keyword {
            "comment" | "obj_info" => {}
            "format" => {
                if encoding.is_some() {
                    return Err((line_no, "second `format` line".to_owned()));
                }
                encoding = Some(parse_format(&words).ok_or_else(|| {
                    (
                        line_no,
                        format!(
                            "bad format line `{}` (expected `format ascii|binary_little_endian|binary_big_endian 1.0`)",
                            text.trim()
                        ),
                    )
                })?);
            }
            "element" => {
                let [_, name, count] = words[..] else {
                    return Err((line_no, "expected `element <name> <count>`".to_owned()));
                };
                let count = count.parse::<usize>().map_err(|_| {
                    (
                        line_no,
                        format!("element `{name}` has a bad count `{count}`"),
                    )
                })?;
                if elements.iter().any(|e| e.name == name) {
                    return Err((line_no, format!("element `{name}` is declared twice")));
                }
                elements.push(Element {
                    name: name.to_owned(),
                    count,
                    properties: Vec::new(),
                    line: line_no,
                });
            }
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err((line_no, "`property` before any `element`".to_owned()));
                };
                element
                    .properties
                    .push(parse_property(&words).map_err(|what| (line_no, what))?);
            }
            "end_header" => {
                let Some(encoding) = encoding else {
                    return Err((line_no, "no `format` line before `end_header`".to_owned()));
                };
                return Ok(Header {
                    encoding,
                    elements,
                    body_start: pos,
                    end_line: line_no,
                });
            }
            other => {
                return Err((line_no, format!("unknown header keyword `{other}`")));
            }
        }
    }
    if line_no == 0 {
        return Err((1, "not a PLY file (it is empty)".to_owned()));
    }
    Err((line_no, "the header has no `end_header` line".to_owned()))
}

fn parse_format(words: &[&str]) -> Option<Encoding> {
    let [_, name, version] = words[..] else {
        return None;
    };
    if version != "1.0" {
        return None;
    }
    match name {
        "ascii" => Some(Encoding::Ascii),
        "binary_little_endian" => Some(Encoding::BinaryLittleEndian),
        "binary_big_endian" => Some(Encoding::BinaryBigEndian),
        _ => None,
    }
}

fn parse_property(words: &[&str]) -> Result<Property, String> {
    let scalar =
        |name: &str| Scalar::parse(name).ok_or_else(|| format!("unknown property type `{name}`"));
    match words[..] {
        [_, "list", count, item, name] => {
            let count = scalar(count)?;
            if !count.is_integer() {
                return Err(format!("list `{name}` has a non-integer length type"));
            }
            Ok(Property {
                name: name.to_owned(),
                ty: PropertyType::List {
                    count,
                    item: scalar(item)?,
                },
            })
        }
        [_, "list", ..] => {
            Err("expected `property list <count type> <item type> <name>`".to_owned())
        }
        [_, ty, name] => Ok(Property {
            name: name.to_owned(),
            ty: PropertyType::Scalar(scalar(ty)?),
        }),
        _ => Err("expected `property <type> <name>`".to_owned()),
    }
}
