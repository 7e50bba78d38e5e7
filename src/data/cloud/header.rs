//! The PLY header: format line, elements, properties and the loudscape metadata (one version-1
//! `comment loudscape-meta {JSON}` line, or the version-2 `comment loudscape-meta-v2 I/N CHUNK`
//! parts, joined), read line by line up to [`MAX_HEADER_BYTES`].

use std::io::{BufRead, Read};
use std::path::Path;

use super::{CloudError, MAX_HEADER_BYTES, META_KEYWORD, META_V2_KEYWORD};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Encoding {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

impl Encoding {
    pub(super) fn name(self) -> &'static str {
        match self {
            Encoding::Ascii => "ascii",
            Encoding::BinaryLittleEndian => "binary_little_endian",
            Encoding::BinaryBigEndian => "binary_big_endian",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum ScalarType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl ScalarType {
    pub(super) fn parse(name: &str) -> Option<ScalarType> {
        Some(match name {
            "char" | "int8" => ScalarType::I8,
            "uchar" | "uint8" => ScalarType::U8,
            "short" | "int16" => ScalarType::I16,
            "ushort" | "uint16" => ScalarType::U16,
            "int" | "int32" => ScalarType::I32,
            "uint" | "uint32" => ScalarType::U32,
            "float" | "float32" => ScalarType::F32,
            "double" | "float64" => ScalarType::F64,
            _ => return None,
        })
    }

    pub(super) fn size(self) -> usize {
        match self {
            ScalarType::I8 | ScalarType::U8 => 1,
            ScalarType::I16 | ScalarType::U16 => 2,
            ScalarType::I32 | ScalarType::U32 | ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }

    /// Reads a little-endian value from the front of `bytes` (which holds at least `size()`).
    pub(super) fn read_le(self, bytes: &[u8]) -> Option<f64> {
        fn take<const N: usize>(bytes: &[u8]) -> Option<[u8; N]> {
            bytes.get(..N)?.try_into().ok()
        }
        Some(match self {
            ScalarType::I8 => f64::from(i8::from_le_bytes(take(bytes)?)),
            ScalarType::U8 => f64::from(u8::from_le_bytes(take(bytes)?)),
            ScalarType::I16 => f64::from(i16::from_le_bytes(take(bytes)?)),
            ScalarType::U16 => f64::from(u16::from_le_bytes(take(bytes)?)),
            ScalarType::I32 => f64::from(i32::from_le_bytes(take(bytes)?)),
            ScalarType::U32 => f64::from(u32::from_le_bytes(take(bytes)?)),
            ScalarType::F32 => f64::from(f32::from_le_bytes(take(bytes)?)),
            ScalarType::F64 => f64::from_le_bytes(take(bytes)?),
        })
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum PropertyKind {
    Scalar(ScalarType),
    List { count: ScalarType, item: ScalarType },
}

#[derive(Clone, Debug)]
pub(super) struct Property {
    pub(super) name: String,
    pub(super) kind: PropertyKind,
    /// The property's text, for messages.
    pub(super) text: String,
    pub(super) line: usize,
}

#[derive(Clone, Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: u64,
    pub(super) line: usize,
    pub(super) properties: Vec<Property>,
}

#[derive(Clone, Debug)]
pub(super) struct Header {
    pub(super) encoding: Encoding,
    pub(super) format_line: usize,
    /// The metadata JSON text and the line it is reported at: the `comment loudscape-meta`
    /// line (version 1) or the first `loudscape-meta-v2` part (version 2, the parts joined).
    pub(super) meta: Option<(usize, String)>,
    pub(super) elements: Vec<Element>,
    pub(super) end_line: usize,
    /// Bytes up to and including the `end_header` line.
    pub(super) byte_len: u64,
}

/// A short, printable excerpt of header bytes for messages.
pub(super) fn excerpt(bytes: &[u8]) -> String {
    let text: String = String::from_utf8_lossy(&bytes[..bytes.len().min(40)])
        .chars()
        .flat_map(char::escape_debug)
        .collect();
    if bytes.len() > 40 {
        format!("`{text}...`")
    } else {
        format!("`{text}`")
    }
}

pub(super) fn parse_header<R: BufRead>(reader: &mut R, path: &Path) -> Result<Header, CloudError> {
    let error = |line: usize, reason: String| CloudError::Header {
        path: path.to_owned(),
        line,
        reason,
    };
    let meta_error = |line: usize, reason: String| CloudError::Meta {
        path: path.to_owned(),
        line,
        reason,
    };
    let mut consumed: u64 = 0;
    let mut line_no = 0;
    let mut buf = Vec::new();
    let mut format: Option<(Encoding, usize)> = None;
    let mut meta: Option<(usize, String)> = None;
    let mut v2 = MetaParts::default();
    let mut elements: Vec<Element> = Vec::new();
    loop {
        line_no += 1;
        buf.clear();
        let n = reader
            .by_ref()
            .take(MAX_HEADER_BYTES - consumed)
            .read_until(b'\n', &mut buf)
            .map_err(|e| error(line_no, format!("cannot read the header: {e}")))?;
        consumed += n as u64;
        let complete = buf.last() == Some(&b'\n');
        if complete {
            buf.pop();
        }
        if buf.last() == Some(&b'\r') {
            buf.pop();
        }
        if line_no == 1 {
            if n == 0 {
                return Err(error(1, "the file is empty (expected a PLY header)".into()));
            }
            if buf.as_slice() != b"ply" {
                return Err(error(
                    1,
                    format!("not a PLY file: expected `ply`, found {}", excerpt(&buf)),
                ));
            }
        }
        let text = std::str::from_utf8(&buf).map_err(|e| {
            error(
                line_no,
                format!(
                    "not valid UTF-8 at column {} (PLY headers are ASCII text)",
                    e.valid_up_to() + 1
                ),
            )
        })?;
        let (keyword, rest) = match text.trim().split_once(char::is_whitespace) {
            Some((keyword, rest)) => (keyword, rest.trim()),
            None => (text.trim(), ""),
        };
        // A comment is not split: its words could number millions (a version-1 metadata line).
        let tokens: Vec<&str> = if keyword == "comment" {
            rest.split_whitespace().take(1).collect()
        } else {
            rest.split_whitespace().collect()
        };
        if !complete && keyword != "end_header" {
            return Err(if consumed >= MAX_HEADER_BYTES {
                error(
                    line_no,
                    format!(
                        "the header is longer than {} MiB, the most loudscape reads \
                         (docs/FORMAT.md, \"Header size\")",
                        MAX_HEADER_BYTES >> 20
                    ),
                )
            } else {
                error(line_no, "the file ends before `end_header`".into())
            });
        }
        match keyword {
            "ply" if line_no == 1 => {}
            "format" => {
                if let Some((_, first)) = format {
                    return Err(error(
                        line_no,
                        format!("second `format` line (the first is line {first})"),
                    ));
                }
                let encoding = match tokens.first() {
                    Some(&"ascii") => Encoding::Ascii,
                    Some(&"binary_little_endian") => Encoding::BinaryLittleEndian,
                    Some(&"binary_big_endian") => Encoding::BinaryBigEndian,
                    _ => {
                        return Err(error(
                            line_no,
                            format!(
                                "unknown format {}: expected `format binary_little_endian 1.0`, \
                                 `format ascii 1.0` or `format binary_big_endian 1.0`",
                                excerpt(text.as_bytes())
                            ),
                        ));
                    }
                };
                if tokens.len() != 2 || !matches!(tokens[1], "1.0" | "1") {
                    return Err(error(
                        line_no,
                        format!(
                            "expected `format {} 1.0`, found {}",
                            encoding.name(),
                            excerpt(text.as_bytes())
                        ),
                    ));
                }
                format = Some((encoding, line_no));
            }
            "comment" => {
                let word = tokens.first().copied().unwrap_or("");
                if word == META_KEYWORD {
                    if let Some((first, _)) = meta {
                        return Err(meta_error(
                            line_no,
                            format!("second loudscape-meta comment (the first is line {first})"),
                        ));
                    }
                    if let Some(first) = v2.first_line {
                        return Err(meta_error(
                            line_no,
                            format!(
                                "both a version-1 loudscape-meta comment and version-2 \
                                 {META_V2_KEYWORD} parts (the first is line {first})"
                            ),
                        ));
                    }
                    meta = Some((line_no, rest[META_KEYWORD.len()..].trim().to_owned()));
                } else if word == META_V2_KEYWORD {
                    if let Some((first, _)) = meta {
                        return Err(meta_error(
                            line_no,
                            format!(
                                "both version-2 {META_V2_KEYWORD} parts and a version-1 \
                                 loudscape-meta comment (line {first})"
                            ),
                        ));
                    }
                    v2.push(text, line_no)
                        .map_err(|reason| meta_error(line_no, reason))?;
                }
            }
            "obj_info" | "" => {}
            "element" => {
                let (name, count) = match tokens.as_slice() {
                    [name, count] => (*name, *count),
                    [name] => {
                        return Err(error(
                            line_no,
                            format!("`element {name}` has no count, e.g. `element {name} 1000`"),
                        ));
                    }
                    _ => {
                        return Err(error(
                            line_no,
                            format!(
                                "expected `element NAME COUNT`, found {}",
                                excerpt(text.as_bytes())
                            ),
                        ));
                    }
                };
                let count: u64 = count.parse().map_err(|_| {
                    error(
                        line_no,
                        format!(
                            "element count {} is not a whole number of at most {}",
                            excerpt(count.as_bytes()),
                            u64::MAX
                        ),
                    )
                })?;
                if let Some(previous) = elements.iter().find(|e| e.name == name) {
                    return Err(error(
                        line_no,
                        format!(
                            "second `element {name}` (the first is line {})",
                            previous.line
                        ),
                    ));
                }
                elements.push(Element {
                    name: name.to_owned(),
                    count,
                    line: line_no,
                    properties: Vec::new(),
                });
            }
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(error(line_no, "`property` before any `element`".into()));
                };
                let scalar = |name: &str| {
                    ScalarType::parse(name).ok_or_else(|| {
                        error(
                            line_no,
                            format!("unknown property type {}", excerpt(name.as_bytes())),
                        )
                    })
                };
                let (kind, name) = match tokens.as_slice() {
                    ["list", count, item, name] => (
                        PropertyKind::List {
                            count: scalar(count)?,
                            item: scalar(item)?,
                        },
                        *name,
                    ),
                    [kind, name] if *kind != "list" => (PropertyKind::Scalar(scalar(kind)?), *name),
                    _ => {
                        return Err(error(
                            line_no,
                            format!(
                                "expected `property TYPE NAME` or `property list COUNT_TYPE \
                                 ITEM_TYPE NAME`, found {}",
                                excerpt(text.as_bytes())
                            ),
                        ));
                    }
                };
                if let Some(previous) = element.properties.iter().find(|p| p.name == name) {
                    return Err(error(
                        line_no,
                        format!(
                            "second property `{name}` in `element {}` (the first is line {})",
                            element.name, previous.line
                        ),
                    ));
                }
                element.properties.push(Property {
                    name: name.to_owned(),
                    kind,
                    text: text.trim().to_owned(),
                    line: line_no,
                });
            }
            "end_header" => {
                if !tokens.is_empty() {
                    return Err(error(
                        line_no,
                        format!(
                            "unexpected text after `end_header`: {}",
                            excerpt(rest.as_bytes())
                        ),
                    ));
                }
                if let Some(first) = v2.first_line {
                    if v2.parts != v2.total {
                        return Err(meta_error(
                            first,
                            format!(
                                "{META_V2_KEYWORD} has {} of its {} parts (the header ends on \
                                 line {line_no})",
                                v2.parts, v2.total
                            ),
                        ));
                    }
                    meta = Some((first, std::mem::take(&mut v2.text)));
                }
                let Some((encoding, format_line)) = format else {
                    return Err(error(
                        line_no,
                        "no `format` line before `end_header` (expected `format \
                         binary_little_endian 1.0` on line 2)"
                            .into(),
                    ));
                };
                return Ok(Header {
                    encoding,
                    format_line,
                    meta,
                    elements,
                    end_line: line_no,
                    byte_len: consumed,
                });
            }
            other => {
                return Err(error(
                    line_no,
                    format!("unknown header keyword {}", excerpt(other.as_bytes())),
                ));
            }
        }
    }
}

/// The version-2 metadata parts seen so far (docs/FORMAT.md, "Version 2 metadata lines").
#[derive(Default)]
struct MetaParts {
    /// Line of part 1.
    first_line: Option<usize>,
    /// `N` of part 1.
    total: u64,
    /// Parts taken so far.
    parts: u64,
    /// Their chunks, joined.
    text: String,
}

impl MetaParts {
    /// Takes the line `comment loudscape-meta-v2 I/N CHUNK` (`line`: its text without `\n` or
    /// `\r`), which must match exactly and be the next part in order.
    fn push(&mut self, line: &str, line_no: usize) -> Result<(), String> {
        let shape = || {
            format!(
                "expected `comment {META_V2_KEYWORD} I/N CHUNK` (one space between words, I and \
                 N whole numbers from 1 without leading zeros, CHUNK printable ASCII without \
                 spaces), found {}",
                excerpt(line.as_bytes())
            )
        };
        let prefix = format!("comment {META_V2_KEYWORD} ");
        let rest = line.strip_prefix(prefix.as_str()).ok_or_else(shape)?;
        let (numbers, chunk) = rest.split_once(' ').ok_or_else(shape)?;
        let (index, total) = numbers.split_once('/').ok_or_else(shape)?;
        let number = |digits: &str| -> Option<u64> {
            let first = *digits.as_bytes().first()?;
            if !(b'1'..=b'9').contains(&first) || !digits.bytes().all(|b| b.is_ascii_digit()) {
                return None;
            }
            digits.parse().ok()
        };
        let (Some(index), Some(total)) = (number(index), number(total)) else {
            return Err(shape());
        };
        if chunk.is_empty() || !chunk.bytes().all(|b| (0x21..=0x7e).contains(&b)) {
            return Err(shape());
        }
        match self.first_line {
            None => {
                if index != 1 {
                    return Err(format!(
                        "{META_V2_KEYWORD} part {index}/{total} comes first (expected 1/{total})"
                    ));
                }
                self.first_line = Some(line_no);
                self.total = total;
            }
            Some(first) => {
                if total != self.total {
                    return Err(format!(
                        "{META_V2_KEYWORD} part {index}/{total}: the part count changed (part 1 \
                         on line {first} says {})",
                        self.total
                    ));
                }
                if index != self.parts + 1 {
                    return Err(format!(
                        "{META_V2_KEYWORD} part {index}/{total} out of order (expected {}/{total})",
                        self.parts + 1
                    ));
                }
            }
        }
        if index > total {
            return Err(format!(
                "{META_V2_KEYWORD} part {index}/{total}: more parts than announced"
            ));
        }
        self.parts = index;
        // Grown by an eighth at a time, not doubled: at most 12.5 % unused (large blocks are
        // remapped, not copied, when they grow).
        if self.text.capacity() - self.text.len() < chunk.len() {
            self.text.reserve_exact(self.text.len() / 8 + chunk.len());
        }
        self.text.push_str(chunk);
        Ok(())
    }
}
