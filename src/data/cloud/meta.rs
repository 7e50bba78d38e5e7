//! The `loudscape-meta` JSON of a header (either format version), typed into [`CloudMeta`],
//! with the exact bytes of non-UTF-8 paths from their `KEY_bytes_b64` companions.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Deserializer};
use serde_json::Value;

use super::{
    Axes, Axis, CloudError, CloudMeta, CloudWarning, DataMode, FORMAT_VERSIONS, Metrics, SongInfo,
    Source, Stft,
};

/// The suffix of a member that holds the exact bytes of its sibling string (docs/FORMAT.md,
/// "Strings that are not UTF-8").
pub(super) const BYTES_SUFFIX: &str = "_bytes_b64";

/// Decodes standard base64 (RFC 4648 section 4: `A-Z a-z 0-9 + /`, `=` padding to a multiple of
/// four characters, no whitespace). Non-canonical trailing bits are refused as Python's
/// `b64decode(validate=True)` would not produce them from bytes.
pub(super) fn decode_base64(text: &str) -> Result<Vec<u8>, String> {
    fn value(byte: u8) -> Option<u32> {
        Some(match byte {
            b'A'..=b'Z' => byte - b'A',
            b'a'..=b'z' => byte - b'a' + 26,
            b'0'..=b'9' => byte - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    }
    let bytes = text.as_bytes();
    if !bytes.len().is_multiple_of(4) {
        return Err(format!(
            "{} characters, not a multiple of 4 (standard base64 with `=` padding)",
            bytes.len()
        ));
    }
    let mut out = Vec::with_capacity(bytes.len() / 4 * 3);
    for (i, quad) in bytes.chunks_exact(4).enumerate() {
        let last = i + 1 == bytes.len() / 4;
        let padding = quad.iter().rev().take_while(|&&b| b == b'=').count();
        if padding > 2 || (padding > 0 && !last) || quad[..4 - padding].contains(&b'=') {
            return Err(format!("misplaced `=` at character {}", i * 4 + 1));
        }
        let mut word = 0u32;
        for (j, &b) in quad[..4 - padding].iter().enumerate() {
            let v = value(b).ok_or_else(|| {
                format!(
                    "character {} ({:?}) is not in the base64 alphabet",
                    i * 4 + j + 1,
                    b as char
                )
            })?;
            word |= v << (18 - 6 * j);
        }
        let decoded = [(word >> 16) as u8, (word >> 8) as u8, word as u8];
        let keep = 3 - padding;
        if decoded[keep..].iter().any(|&b| b != 0) {
            return Err("non-zero bits after the last byte".into());
        }
        out.extend_from_slice(&decoded[..keep]);
    }
    Ok(out)
}

/// Checks every `*_bytes_b64` member in `value` (a string of valid base64); `at` is the JSON
/// path of `value`, for messages.
fn check_bytes_members(value: &Value, at: &mut String) -> Result<(), String> {
    match value {
        Value::Object(object) => {
            for (key, item) in object {
                let len = at.len();
                if !at.is_empty() {
                    at.push('.');
                }
                at.push_str(key);
                if key.ends_with(BYTES_SUFFIX) {
                    let Value::String(text) = item else {
                        return Err(format!("`{at}` must be a base64 string, found {item}"));
                    };
                    decode_base64(text).map_err(|e| format!("`{at}` is not base64: {e}"))?;
                } else {
                    check_bytes_members(item, at)?;
                }
                at.truncate(len);
            }
        }
        Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                let len = at.len();
                at.push_str(&format!("[{i}]"));
                check_bytes_members(item, at)?;
                at.truncate(len);
            }
        }
        _ => {}
    }
    Ok(())
}

/// The exact bytes of `object.KEY` from `object.KEY_bytes_b64` (already checked), if any.
fn exact_bytes(object: Option<&Value>, key: &str) -> Option<Vec<u8>> {
    let text = object?.get(format!("{key}{BYTES_SUFFIX}"))?.as_str()?;
    decode_base64(text).ok()
}

/// The path to open for a recorded path: its exact bytes when the file recorded them (on Unix a
/// file name is bytes; elsewhere the bytes are read as UTF-8 with U+FFFD for invalid ones), else
/// the text.
pub(super) fn open_path(text: Option<&str>, bytes: Option<&[u8]>) -> Option<PathBuf> {
    match bytes {
        #[cfg(unix)]
        Some(bytes) => {
            use std::os::unix::ffi::OsStrExt;
            Some(PathBuf::from(std::ffi::OsStr::from_bytes(bytes)))
        }
        #[cfg(not(unix))]
        Some(bytes) => Some(PathBuf::from(String::from_utf8_lossy(bytes).into_owned())),
        None => text.map(PathBuf::from),
    }
}

pub(super) fn lenient_u32<'de, D: Deserializer<'de>>(
    deserializer: D,
) -> Result<Option<u32>, D::Error> {
    lenient_integer(deserializer)
}

pub(super) fn lenient_i32<'de, D: Deserializer<'de>>(
    deserializer: D,
) -> Result<Option<i32>, D::Error> {
    lenient_integer(deserializer)
}

/// A whole number that may be written as `44100` or `44100.0`; `null` is None.
pub(super) fn lenient_integer<'de, D, T>(deserializer: D) -> Result<Option<T>, D::Error>
where
    D: Deserializer<'de>,
    T: TryFrom<i64>,
{
    use serde::de::Error;
    let value = Option::<f64>::deserialize(deserializer)?;
    match value {
        None => Ok(None),
        Some(v) if v.fract() == 0.0 && v.abs() < 1e15 => T::try_from(v as i64)
            .map(Some)
            .map_err(|_| D::Error::custom(format!("{v} is out of range"))),
        Some(v) => Err(D::Error::custom(format!(
            "expected a whole number, found {v}"
        ))),
    }
}

pub(super) fn parse_meta(json: &str, line: usize, path: &Path) -> Result<CloudMeta, CloudError> {
    let error = |reason: String| CloudError::Meta {
        path: path.to_owned(),
        line,
        reason,
    };
    // What the values would take, counted before they are built: metadata made of tiny values
    // (`[0,0,0,...]`) would take tens of times its text.
    let cost = value_cost(json).unwrap_or(0);
    let budget = MAX_META_FACTOR * json.len() as u64 + META_BASE_BYTES;
    if cost > budget {
        return Err(error(format!(
            "the metadata would take about {} MB in memory, more than {MAX_META_FACTOR} times its \
             {} MB of text (docs/FORMAT.md, \"Header size\")",
            cost.div_ceil(1 << 20),
            (json.len() as u64).div_ceil(1 << 20)
        )));
    }
    let raw: Value = serde_json::from_str(json).map_err(|e| {
        error(if e.to_string().starts_with("recursion limit exceeded") {
            format!(
                "the JSON nests deeper than {MAX_JSON_DEPTH} levels (column {}); loudscape \
                 metadata is a few levels deep",
                e.column()
            )
        } else {
            format!("invalid JSON: {e}")
        })
    })?;
    let Some(object) = raw.as_object() else {
        return Err(error("expected a JSON object `{...}`".into()));
    };
    match object.get("format_version") {
        None => return Err(error("missing `format_version`".into())),
        Some(v) if v.as_u64().is_some_and(|v| FORMAT_VERSIONS.contains(&v)) => {}
        Some(v) => {
            return Err(error(format!(
                "format_version {v} is not supported (this build reads format_version {})",
                FORMAT_VERSIONS.map(|v| v.to_string()).join(" and ")
            )));
        }
    }
    check_bytes_members(&raw, &mut String::new()).map_err(error)?;
    let mode = match object.get("mode") {
        None => return Err(error("missing `mode`".into())),
        Some(Value::String(s)) if s == "song" => DataMode::Song,
        Some(Value::String(s)) if s == "timeline" => DataMode::Timeline,
        Some(v) => {
            return Err(error(format!(
                "`mode` must be \"song\" or \"timeline\", found {v}"
            )));
        }
    };
    let Some(axes_value) = object.get("axes") else {
        return Err(error("missing `axes`".into()));
    };
    let Some(axes_object) = axes_value.as_object() else {
        return Err(error(format!(
            "`axes` must be an object, found {axes_value}"
        )));
    };
    let axis = |name: &str| -> Result<Axis, CloudError> {
        let value = axes_object
            .get(name)
            .ok_or_else(|| error(format!("`axes` has no `{name}` axis")))?;
        let axis: Axis = serde_json::from_value(value.clone())
            .map_err(|e| error(format!("`axes.{name}`: {e}")))?;
        if let Some(problem) = axis.problem() {
            return Err(error(format!("`axes.{name}`: {problem}")));
        }
        Ok(axis)
    };
    let axes = Axes {
        x: axis("x")?,
        y: axis("y")?,
        z: axis("z")?,
        scalar: axis("scalar")?,
        hp: axis("hp")?,
    };
    let point_count = match object.get("point_count") {
        None | Some(Value::Null) => None,
        Some(v) => Some(
            v.as_u64()
                .ok_or_else(|| error(format!("`point_count` must be a whole number, found {v}")))?,
        ),
    };
    pub(super) fn optional<T: serde::de::DeserializeOwned>(
        object: &serde_json::Map<String, Value>,
        key: &str,
    ) -> Result<Option<T>, String> {
        match object.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(v) => serde_json::from_value(v.clone())
                .map(Some)
                .map_err(|e| format!("`{key}`: {e}")),
        }
    }
    let mut source = optional::<Source>(object, "source").map_err(error)?;
    if let Some(source) = &mut source {
        source.path_bytes = exact_bytes(object.get("source"), "path");
    }
    let stft = optional::<Stft>(object, "stft").map_err(error)?;
    let metrics = optional::<Metrics>(object, "metrics").map_err(error)?;
    let songs = match object.get("songs") {
        None | Some(Value::Null) => Vec::new(),
        Some(Value::Array(items)) => items
            .iter()
            .enumerate()
            .map(|(i, item)| {
                let mut song = serde_json::from_value::<SongInfo>(item.clone())
                    .map_err(|e| error(format!("`songs[{i}]`: {e}")))?;
                song.path_bytes = exact_bytes(Some(item), "path");
                Ok(song)
            })
            .collect::<Result<_, _>>()?,
        Some(v) => return Err(error(format!("`songs` must be an array, found {v}"))),
    };
    let warnings = parse_warnings(object.get("warnings")).map_err(error)?;
    Ok(CloudMeta {
        mode,
        axes,
        point_count,
        source,
        stft,
        metrics,
        songs,
        warnings,
        raw,
    })
}

/// The metadata's JSON values may take at most this many times the size of its text, plus
/// [`META_BASE_BYTES`] (docs/FORMAT.md, "Header size").
pub const MAX_META_FACTOR: u64 = 6;
/// Room any metadata has, whatever its shape (a short song's loudness curves are small numbers).
pub const META_BASE_BYTES: u64 = 16 << 20;

/// Bytes the `serde_json::Value` tree of `json` would take, counted in one pass that builds
/// nothing: each value's 32 bytes, the heap of each string, an array's unused capacity (it grows
/// by doubling) and an object's B-tree nodes (about 1.5 times key and value per member).
/// Errors are those of the JSON (left to the real parse to report).
pub(super) fn value_cost(json: &str) -> Result<u64, serde_json::Error> {
    use serde::de::{DeserializeSeed, MapAccess, SeqAccess, Visitor};
    const VALUE: u64 = 32;
    const STRING: u64 = 24;
    struct Cost<'a>(&'a mut u64);
    impl<'de> DeserializeSeed<'de> for Cost<'_> {
        type Value = ();
        fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<(), D::Error> {
            deserializer.deserialize_any(self)
        }
    }
    impl<'de> Visitor<'de> for Cost<'_> {
        type Value = ();
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("JSON")
        }
        fn visit_bool<E: serde::de::Error>(self, _: bool) -> Result<(), E> {
            *self.0 += VALUE;
            Ok(())
        }
        fn visit_i64<E: serde::de::Error>(self, _: i64) -> Result<(), E> {
            *self.0 += VALUE;
            Ok(())
        }
        fn visit_u64<E: serde::de::Error>(self, _: u64) -> Result<(), E> {
            *self.0 += VALUE;
            Ok(())
        }
        fn visit_f64<E: serde::de::Error>(self, _: f64) -> Result<(), E> {
            *self.0 += VALUE;
            Ok(())
        }
        fn visit_unit<E: serde::de::Error>(self) -> Result<(), E> {
            *self.0 += VALUE;
            Ok(())
        }
        fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<(), E> {
            *self.0 += VALUE + v.len() as u64;
            Ok(())
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
            let mut n = 0u64;
            while seq.next_element_seed(Cost(&mut *self.0))?.is_some() {
                n += 1;
            }
            *self.0 += VALUE + (n.next_power_of_two() - n) * VALUE;
            Ok(())
        }
        fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
            *self.0 += VALUE;
            while let Some(key) = map.next_key::<std::borrow::Cow<'de, str>>()? {
                let mut value = 0u64;
                map.next_value_seed(Cost(&mut value))?;
                // The value's own 32 bytes sit in the node, with the key's 24: half as much
                // again for the nodes' unused slots.
                *self.0 +=
                    (STRING + VALUE) * 3 / 2 + key.len() as u64 + value.saturating_sub(VALUE);
            }
            Ok(())
        }
    }
    let mut total = 0u64;
    let mut deserializer = serde_json::Deserializer::from_str(json);
    Cost(&mut total).deserialize(&mut deserializer)?;
    Ok(total)
}

/// serde_json's nesting limit: deeper JSON is refused before it could exhaust the stack.
const MAX_JSON_DEPTH: usize = 128;

/// The longest warning message kept, in characters (a longer one is cut, with `...`).
const MAX_WARNING_CHARS: usize = 1000;

/// One line of text for a terminal: control characters (newlines, escapes) become spaces, and
/// at most [`MAX_WARNING_CHARS`] characters.
pub fn one_line(text: &str) -> String {
    let mut out: String = text
        .chars()
        .take(MAX_WARNING_CHARS)
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    if text.chars().nth(MAX_WARNING_CHARS).is_some() {
        out.push_str("...");
    }
    out.trim().to_string()
}

/// The `warnings` array (docs/FORMAT.md, "Warnings"): objects with a string `message`, a
/// string `kind` and, in timeline mode, a string `path`. Absent or `null` is none; anything else
/// is refused, as a warning that cannot be read must not vanish.
fn parse_warnings(value: Option<&Value>) -> Result<Vec<CloudWarning>, String> {
    let items = match value {
        None | Some(Value::Null) => return Ok(Vec::new()),
        Some(Value::Array(items)) => items,
        Some(v) => return Err(format!("`warnings` must be an array, found {}", short(v))),
    };
    items
        .iter()
        .enumerate()
        .map(|(i, item)| {
            let text = |key: &str, required: bool| -> Result<Option<String>, String> {
                match item.get(key) {
                    Some(Value::String(s)) => Ok(Some(one_line(s))),
                    None | Some(Value::Null) if !required => Ok(None),
                    None => Err(format!("`warnings[{i}]` has no string `{key}`")),
                    Some(v) => Err(format!(
                        "`warnings[{i}].{key}` must be a string, found {}",
                        short(v)
                    )),
                }
            };
            if !item.is_object() {
                return Err(format!(
                    "`warnings[{i}]` must be an object {{\"kind\", \"message\"}}, found {}",
                    short(item)
                ));
            }
            Ok(CloudWarning {
                kind: text("kind", true)?.unwrap_or_default(),
                message: text("message", true)?.unwrap_or_default(),
                path: text("path", false)?,
            })
        })
        .collect()
}

/// A JSON value for a message: at most 60 characters of it.
fn short(value: &Value) -> String {
    let text = value.to_string();
    match text.char_indices().nth(60) {
        Some((cut, _)) => format!("{}...", &text[..cut]),
        None => text,
    }
}

/// Song mode's loudness over time (docs/FORMAT.md, "loudness"): momentary and short-term
/// loudness, PSR and the true-peak overs. Files without it (older extractors, other tools)
/// have none; a malformed object is treated as absent, so the cloud still opens.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoudnessCurves {
    /// Values per second of each curve.
    pub rate_hz: f64,
    /// Centre time of the first momentary (400 ms) window, seconds.
    pub momentary_start_s: f64,
    pub momentary_lufs: Vec<Option<f32>>,
    /// Centre time of the first short-term (3 s) window, seconds; PSR shares its windows.
    pub short_term_start_s: f64,
    pub short_term_lufs: Vec<Option<f32>>,
    pub psr_db: Vec<Option<f32>>,
    /// `[start_s, end_s]` where the true peak exceeds 0 dBTP, and -1 dBTP.
    pub overs_0dbtp: Vec<(f64, f64)>,
    pub overs_1dbtp: Vec<(f64, f64)>,
}

impl LoudnessCurves {
    /// The time of value `index` of a curve starting at `start_s`.
    pub fn time_of(&self, start_s: f64, index: usize) -> f64 {
        start_s + index as f64 / self.rate_hz
    }

    /// The time the curves cover: the last short-term or momentary window's centre plus its
    /// half width.
    pub fn end_s(&self) -> f64 {
        let momentary = self.momentary_lufs.len().saturating_sub(1);
        let short = self.short_term_lufs.len().saturating_sub(1);
        (self.time_of(self.momentary_start_s, momentary) + self.momentary_start_s)
            .max(self.time_of(self.short_term_start_s, short) + self.short_term_start_s)
    }
}

/// The `loudness` object of a file's metadata (`raw`: [`CloudMeta::raw`]), if it has a valid
/// one.
pub fn loudness_curves(raw: &Value) -> Option<LoudnessCurves> {
    let object = raw.get("loudness")?.as_object()?;
    let number = |key: &str| object.get(key).and_then(Value::as_f64);
    let series = |key: &str| -> Option<Vec<Option<f32>>> {
        object
            .get(key)?
            .as_array()?
            .iter()
            .map(|v| match v {
                Value::Null => Some(None),
                v => v.as_f64().map(|x| Some(x as f32)),
            })
            .collect()
    };
    let intervals = |key: &str| -> Option<Vec<(f64, f64)>> {
        match object.get(key) {
            None => Some(Vec::new()),
            Some(v) => v
                .as_array()?
                .iter()
                .map(|pair| {
                    let pair = pair.as_array()?;
                    match pair.as_slice() {
                        [a, b] => Some((a.as_f64()?, b.as_f64()?)),
                        _ => None,
                    }
                })
                .collect(),
        }
    };
    let rate_hz = number("rate_hz").filter(|r| r.is_finite() && *r > 0.0)?;
    Some(LoudnessCurves {
        rate_hz,
        momentary_start_s: number("momentary_start_s").unwrap_or(0.2),
        momentary_lufs: series("momentary_lufs").unwrap_or_default(),
        short_term_start_s: number("short_term_start_s").unwrap_or(1.5),
        short_term_lufs: series("short_term_lufs")?,
        psr_db: series("psr_db").unwrap_or_default(),
        overs_0dbtp: intervals("overs_0dbtp")?,
        overs_1dbtp: intervals("overs_1dbtp")?,
    })
}

#[cfg(test)]
mod loudness_tests {
    use super::*;

    #[test]
    fn warnings_are_read_kept_to_one_line_and_malformed_ones_refused() {
        let parse = |json: &str| parse_warnings(Some(&serde_json::from_str(json).unwrap()));
        assert!(parse("null").unwrap().is_empty());
        assert!(parse("[]").unwrap().is_empty());
        let read = parse(
            r#"[{"kind": "truncated", "message": "decoded 1.49 s of the 4.00 s the file promises"},
               {"kind": "clipping", "message": "two\nlines\u001b[31m", "path": "a.wav"}]"#,
        )
        .unwrap();
        assert_eq!(read[0].kind, "truncated");
        assert_eq!(read[0].path, None);
        assert_eq!(read[1].message, "two lines [31m");
        assert_eq!(read[1].path.as_deref(), Some("a.wav"));
        for bad in [
            r#"{"kind": "x"}"#,
            r#"["text"]"#,
            r#"[{"kind": "x"}]"#,
            r#"[{"kind": "x", "message": 3}]"#,
            r#"[{"message": "m"}]"#,
            r#"[{"kind": "x", "message": "m", "path": 1}]"#,
        ] {
            let error = parse(bad).expect_err(bad);
            assert!(error.contains("warnings"), "{error}");
        }
        let long = one_line(&"x".repeat(5000));
        assert_eq!(long.len(), MAX_WARNING_CHARS + 3);
    }

    #[test]
    fn loudness_curves_are_read_and_files_without_them_have_none() {
        let raw: Value = serde_json::from_str(
            r#"{"loudness": {"rate_hz": 10.0, "momentary_start_s": 0.2,
                "momentary_lufs": [-20.5, null, -18.0], "short_term_start_s": 1.5,
                "short_term_lufs": [-19.0], "psr_db": [12.5],
                "overs_0dbtp": [[1.0, 1.3]], "overs_0dbtp_count": 1,
                "overs_1dbtp": [[1.0, 1.3], [5.0, 5.1]], "overs_1dbtp_count": 2}}"#,
        )
        .unwrap();
        let curves = loudness_curves(&raw).expect("curves");
        assert_eq!(curves.momentary_lufs, [Some(-20.5), None, Some(-18.0)]);
        assert_eq!(curves.short_term_lufs, [Some(-19.0)]);
        assert_eq!(curves.psr_db, [Some(12.5)]);
        assert_eq!(curves.overs_0dbtp, [(1.0, 1.3)]);
        assert_eq!(curves.overs_1dbtp, [(1.0, 1.3), (5.0, 5.1)]);
        assert!((curves.time_of(curves.momentary_start_s, 2) - 0.4).abs() < 1e-12);
        assert!((curves.end_s() - 3.0).abs() < 1e-12);
        assert_eq!(loudness_curves(&serde_json::json!({"mode": "song"})), None);
        // malformed: absent, not an error
        let bad = serde_json::json!({"loudness": {"rate_hz": 10.0, "short_term_lufs": "x"}});
        assert_eq!(loudness_curves(&bad), None);
    }
}
