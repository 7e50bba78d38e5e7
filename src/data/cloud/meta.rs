//! The `loudscape-meta` JSON of a header, typed into [`CloudMeta`].

use std::path::Path;

use serde::{Deserialize, Deserializer};
use serde_json::Value;

use super::{
    Axes, Axis, CloudError, CloudMeta, DataMode, FORMAT_VERSION, Metrics, SongInfo, Source, Stft,
};

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
    let raw: Value = serde_json::from_str(json).map_err(|e| error(format!("invalid JSON: {e}")))?;
    let Some(object) = raw.as_object() else {
        return Err(error("expected a JSON object `{...}`".into()));
    };
    match object.get("format_version") {
        None => return Err(error("missing `format_version`".into())),
        Some(v) if v.as_u64() == Some(FORMAT_VERSION) => {}
        Some(v) => {
            return Err(error(format!(
                "format_version {v} is not supported (this build reads format_version \
                 {FORMAT_VERSION})"
            )));
        }
    }
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
    let source = optional::<Source>(object, "source").map_err(error)?;
    let stft = optional::<Stft>(object, "stft").map_err(error)?;
    let metrics = optional::<Metrics>(object, "metrics").map_err(error)?;
    let songs = match object.get("songs") {
        None | Some(Value::Null) => Vec::new(),
        Some(Value::Array(items)) => items
            .iter()
            .enumerate()
            .map(|(i, item)| {
                serde_json::from_value::<SongInfo>(item.clone())
                    .map_err(|e| error(format!("`songs[{i}]`: {e}")))
            })
            .collect::<Result<_, _>>()?,
        Some(v) => return Err(error(format!("`songs` must be an array, found {v}"))),
    };
    Ok(CloudMeta {
        mode,
        axes,
        point_count,
        source,
        stft,
        metrics,
        songs,
        raw,
    })
}
