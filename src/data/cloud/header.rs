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

/// Reads the header from `reader` (positioned at the file's start) up to `end_header`: one
/// [`HeaderParser`] method per keyword.
pub(super) fn parse_header<R: BufRead>(reader: &mut R, path: &Path) -> Result<Header, CloudError> {
    let mut parser = HeaderParser::new(path);
    let mut buf = Vec::new();
    loop {
        let complete = parser.read_line(reader, &mut buf)?;
        let line = parser.split(&buf, complete)?;
        match line.keyword {
            "ply" if parser.line_no == 1 => {}
            "format" => parser.format(&line)?,
            "comment" => parser.comment(&line)?,
            "obj_info" | "" => {}
            "element" => parser.element(&line)?,
            "property" => parser.property(&line)?,
            "end_header" => return parser.end_header(&line),
            other => {
                return Err(parser.error(format!(
                    "unknown header keyword {}",
                    excerpt(other.as_bytes())
                )));
            }
        }
    }
}

/// One header line, split into its keyword and the words after it.
struct Line<'t> {
    /// The line without its `\n` or `\r\n`.
    text: &'t str,
    keyword: &'t str,
    /// The text after the keyword, trimmed.
    rest: &'t str,
    /// The words of `rest` (of a comment, only the first: a version-1 metadata line could
    /// hold millions).
    tokens: Vec<&'t str>,
}

/// What the header said so far, line by line; each keyword has its method.
struct HeaderParser<'p> {
    path: &'p Path,
    /// Bytes read so far, `end_header`'s line included once it is read.
    consumed: u64,
    /// The line being parsed, from 1.
    line_no: usize,
    format: Option<(Encoding, usize)>,
    meta: Option<(usize, String)>,
    v2: MetaParts,
    elements: Vec<Element>,
}

impl<'p> HeaderParser<'p> {
    fn new(path: &'p Path) -> HeaderParser<'p> {
        HeaderParser {
            path,
            consumed: 0,
            line_no: 0,
            format: None,
            meta: None,
            v2: MetaParts::default(),
            elements: Vec::new(),
        }
    }

    /// A header error at the current line.
    fn error(&self, reason: String) -> CloudError {
        self.error_at(self.line_no, reason)
    }

    fn error_at(&self, line: usize, reason: String) -> CloudError {
        CloudError::Header {
            path: self.path.to_owned(),
            line,
            reason,
        }
    }

    /// A metadata error at `line`.
    fn meta_error_at(&self, line: usize, reason: String) -> CloudError {
        CloudError::Meta {
            path: self.path.to_owned(),
            line,
            reason,
        }
    }

    /// Reads the next line into `buf` (without `\n` or `\r\n`), never past
    /// [`MAX_HEADER_BYTES`]; checks the first line is `ply`. Returns whether the line ended
    /// with `\n`.
    fn read_line<R: BufRead>(
        &mut self,
        reader: &mut R,
        buf: &mut Vec<u8>,
    ) -> Result<bool, CloudError> {
        self.line_no += 1;
        buf.clear();
        let n = reader
            .by_ref()
            .take(MAX_HEADER_BYTES - self.consumed)
            .read_until(b'\n', buf)
            .map_err(|e| self.error(format!("cannot read the header: {e}")))?;
        self.consumed += n as u64;
        let complete = buf.last() == Some(&b'\n');
        if complete {
            buf.pop();
        }
        if buf.last() == Some(&b'\r') {
            buf.pop();
        }
        if self.line_no == 1 {
            if n == 0 {
                return Err(self.error("the file is empty (expected a PLY header)".into()));
            }
            if buf.as_slice() != b"ply" {
                return Err(self.error(format!(
                    "not a PLY file: expected `ply`, found {}",
                    excerpt(buf)
                )));
            }
        }
        Ok(complete)
    }

    /// Splits the line just read; a line that does not end (the file's end, or the size
    /// limit) is an error unless it is `end_header`.
    fn split<'t>(&self, buf: &'t [u8], complete: bool) -> Result<Line<'t>, CloudError> {
        let text = std::str::from_utf8(buf).map_err(|e| {
            self.error(format!(
                "not valid UTF-8 at column {} (PLY headers are ASCII text)",
                e.valid_up_to() + 1
            ))
        })?;
        let (keyword, rest) = match text.trim().split_once(char::is_whitespace) {
            Some((keyword, rest)) => (keyword, rest.trim()),
            None => (text.trim(), ""),
        };
        let tokens: Vec<&str> = if keyword == "comment" {
            rest.split_whitespace().take(1).collect()
        } else {
            rest.split_whitespace().collect()
        };
        if !complete && keyword != "end_header" {
            return Err(if self.consumed >= MAX_HEADER_BYTES {
                self.error(format!(
                    "the header is longer than {} MiB, the most loudscape reads \
                     (docs/FORMAT.md, \"Header size\")",
                    MAX_HEADER_BYTES >> 20
                ))
            } else {
                self.error("the file ends before `end_header`".into())
            });
        }
        Ok(Line {
            text,
            keyword,
            rest,
            tokens,
        })
    }

    /// `format ascii|binary_little_endian|binary_big_endian 1.0`, once.
    fn format(&mut self, line: &Line) -> Result<(), CloudError> {
        if let Some((_, first)) = self.format {
            return Err(self.error(format!("second `format` line (the first is line {first})")));
        }
        let encoding = match line.tokens.first() {
            Some(&"ascii") => Encoding::Ascii,
            Some(&"binary_little_endian") => Encoding::BinaryLittleEndian,
            Some(&"binary_big_endian") => Encoding::BinaryBigEndian,
            _ => {
                return Err(self.error(format!(
                    "unknown format {}: expected `format binary_little_endian 1.0`, \
                     `format ascii 1.0` or `format binary_big_endian 1.0`",
                    excerpt(line.text.as_bytes())
                )));
            }
        };
        if line.tokens.len() != 2 || !matches!(line.tokens[1], "1.0" | "1") {
            return Err(self.error(format!(
                "expected `format {} 1.0`, found {}",
                encoding.name(),
                excerpt(line.text.as_bytes())
            )));
        }
        self.format = Some((encoding, self.line_no));
        Ok(())
    }

    /// A comment: the version-1 metadata line, a version-2 part, or any other (ignored).
    fn comment(&mut self, line: &Line) -> Result<(), CloudError> {
        let word = line.tokens.first().copied().unwrap_or("");
        if word == META_KEYWORD {
            if let Some((first, _)) = self.meta {
                return Err(self.meta_error_at(
                    self.line_no,
                    format!("second loudscape-meta comment (the first is line {first})"),
                ));
            }
            if let Some(first) = self.v2.first_line {
                return Err(self.meta_error_at(
                    self.line_no,
                    format!(
                        "both a version-1 loudscape-meta comment and version-2 \
                         {META_V2_KEYWORD} parts (the first is line {first})"
                    ),
                ));
            }
            self.meta = Some((
                self.line_no,
                line.rest[META_KEYWORD.len()..].trim().to_owned(),
            ));
        } else if word == META_V2_KEYWORD {
            if let Some((first, _)) = self.meta {
                return Err(self.meta_error_at(
                    self.line_no,
                    format!(
                        "both version-2 {META_V2_KEYWORD} parts and a version-1 \
                         loudscape-meta comment (line {first})"
                    ),
                ));
            }
            let line_no = self.line_no;
            if let Err(reason) = self.v2.push(line.text, line_no) {
                return Err(self.meta_error_at(line_no, reason));
            }
        }
        Ok(())
    }

    /// `element NAME COUNT`, each name once.
    fn element(&mut self, line: &Line) -> Result<(), CloudError> {
        let (name, count) = match line.tokens.as_slice() {
            [name, count] => (*name, *count),
            [name] => {
                return Err(self.error(format!(
                    "`element {name}` has no count, e.g. `element {name} 1000`"
                )));
            }
            _ => {
                return Err(self.error(format!(
                    "expected `element NAME COUNT`, found {}",
                    excerpt(line.text.as_bytes())
                )));
            }
        };
        let count: u64 = count.parse().map_err(|_| {
            self.error(format!(
                "element count {} is not a whole number of at most {}",
                excerpt(count.as_bytes()),
                u64::MAX
            ))
        })?;
        if let Some(previous) = self.elements.iter().find(|e| e.name == name) {
            return Err(self.error(format!(
                "second `element {name}` (the first is line {})",
                previous.line
            )));
        }
        self.elements.push(Element {
            name: name.to_owned(),
            count,
            line: self.line_no,
            properties: Vec::new(),
        });
        Ok(())
    }

    /// `property TYPE NAME` or `property list COUNT_TYPE ITEM_TYPE NAME` of the last element,
    /// each name once.
    fn property(&mut self, line: &Line) -> Result<(), CloudError> {
        let scalar = |name: &str| {
            ScalarType::parse(name).ok_or_else(|| {
                self.error(format!(
                    "unknown property type {}",
                    excerpt(name.as_bytes())
                ))
            })
        };
        let Some(element) = self.elements.last() else {
            return Err(self.error("`property` before any `element`".into()));
        };
        let (kind, name) = match line.tokens.as_slice() {
            ["list", count, item, name] => (
                PropertyKind::List {
                    count: scalar(count)?,
                    item: scalar(item)?,
                },
                *name,
            ),
            [kind, name] if *kind != "list" => (PropertyKind::Scalar(scalar(kind)?), *name),
            _ => {
                return Err(self.error(format!(
                    "expected `property TYPE NAME` or `property list COUNT_TYPE \
                     ITEM_TYPE NAME`, found {}",
                    excerpt(line.text.as_bytes())
                )));
            }
        };
        if let Some(previous) = element.properties.iter().find(|p| p.name == name) {
            return Err(self.error(format!(
                "second property `{name}` in `element {}` (the first is line {})",
                element.name, previous.line
            )));
        }
        let property = Property {
            name: name.to_owned(),
            kind,
            text: line.text.trim().to_owned(),
            line: self.line_no,
        };
        if let Some(element) = self.elements.last_mut() {
            element.properties.push(property);
        }
        Ok(())
    }

    /// `end_header`: the version-2 parts complete, a `format` line seen; the header.
    fn end_header(mut self, line: &Line) -> Result<Header, CloudError> {
        if !line.tokens.is_empty() {
            return Err(self.error(format!(
                "unexpected text after `end_header`: {}",
                excerpt(line.rest.as_bytes())
            )));
        }
        if let Some(first) = self.v2.first_line {
            if self.v2.parts != self.v2.total {
                return Err(self.meta_error_at(
                    first,
                    format!(
                        "{META_V2_KEYWORD} has {} of its {} parts (the header ends on \
                         line {})",
                        self.v2.parts, self.v2.total, self.line_no
                    ),
                ));
            }
            self.meta = Some((first, std::mem::take(&mut self.v2.text)));
        }
        let Some((encoding, format_line)) = self.format else {
            return Err(self.error(
                "no `format` line before `end_header` (expected `format \
                 binary_little_endian 1.0` on line 2)"
                    .into(),
            ));
        };
        Ok(Header {
            encoding,
            format_line,
            meta: self.meta,
            elements: self.elements,
            end_line: self.line_no,
            byte_len: self.consumed,
        })
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
