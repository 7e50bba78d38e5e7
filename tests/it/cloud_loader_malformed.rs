//! The PLY loader against malformed files: one test per case, each checking that the error
//! is one line naming the file, the place (header line or byte offset) and the reason.

use std::path::Path;

use loudscape::data::cloud;
use serde_json::{Value, json};

use crate::loader_files::*;

// ---------------------------------------------------------------------------------------------
// Malformed files: one test per case

#[test]
fn truncated_body() {
    let bytes = valid_bytes();
    let end = bytes.len() - 7;
    let offset = end.to_string();
    expect_error(
        "truncated.ply",
        &bytes[..end],
        &[
            "truncated body",
            &format!("byte {offset}"),
            "header line 4",
            "10 points",
            "193 bytes",
        ],
    );
}

#[test]
fn trailing_bytes() {
    let mut bytes = valid_bytes();
    let end = bytes.len();
    bytes.extend_from_slice(b"xyz");
    expect_error(
        "trailing.ply",
        &bytes,
        &[&format!("byte {end}"), "3 trailing bytes", "10 points"],
    );
}

#[test]
fn wrong_magic() {
    let mut bytes = valid_bytes();
    bytes[2] = b'x';
    expect_error(
        "magic.ply",
        &bytes,
        &["header line 1", "not a PLY file", "`plx`"],
    );
    expect_error(
        "magic_png.ply",
        b"\x89PNG\r\n\x1a\n",
        &["header line 1", "not a PLY file"],
    );
}

#[test]
fn wrong_format_line() {
    let bytes = with_header_line(2, "format binary_big_endian 1.0");
    expect_error(
        "big_endian.ply",
        &bytes,
        &["header line 2", "binary_little_endian"],
    );
    let bytes = with_header_line(2, "format binary_little_endian 2.0");
    expect_error(
        "version.ply",
        &bytes,
        &[
            "header line 2",
            "expected `format binary_little_endian 1.0`",
        ],
    );
    let bytes = with_header_line(2, "format ascii 1.0");
    expect_error(
        "ascii_loudscape.ply",
        &bytes,
        &["header line 2", "must be `format binary_little_endian"],
    );
    let bytes = with_header_line(2, "format zip 1.0");
    expect_error("zip.ply", &bytes, &["header line 2", "unknown format"]);
}

#[test]
fn wrong_count() {
    let mut meta = song_meta();
    meta["point_count"] = json!(9);
    let mut bytes = header_text(&STANDARD)
        .replace("element vertex 10", "element vertex 9")
        .replace(&song_meta().to_string(), &meta.to_string())
        .into_bytes();
    let end = bytes.len() + 9 * 20;
    bytes.extend_from_slice(bytemuck::cast_slice(&sample_points(10)));
    expect_error(
        "count_low.ply",
        &bytes,
        &[&format!("byte {end}"), "20 trailing bytes", "header line 4"],
    );
    // The header and the metadata disagree.
    let bytes = with_header_line(4, "element vertex 11");
    expect_error(
        "count_meta.ply",
        &bytes,
        &[
            "header line 3",
            "point_count 10 does not match `element vertex 11`",
        ],
    );
}

#[test]
fn missing_count() {
    let bytes = with_header_line(4, "element vertex");
    expect_error("no_count.ply", &bytes, &["header line 4", "no count"]);
    let bytes = with_header_line(4, "element vertex ten");
    expect_error(
        "word_count.ply",
        &bytes,
        &["header line 4", "`ten` is not a whole number"],
    );
    let bytes = with_header_line(4, "element vertex -10");
    expect_error(
        "negative_count.ply",
        &bytes,
        &["header line 4", "not a whole number"],
    );
}

#[test]
fn wrong_property_name() {
    let bytes = with_header_line(7, "property float w");
    expect_error(
        "name.ply",
        &bytes,
        &[
            "header line 7",
            "expected `property float z`, found `property float w`",
        ],
    );
}

#[test]
fn wrong_property_type() {
    let bytes = with_header_line(8, "property double scalar");
    expect_error(
        "double.ply",
        &bytes,
        &[
            "header line 8",
            "expected `property float scalar`, found `property double scalar`",
        ],
    );
    let bytes = with_header_line(8, "property half scalar");
    expect_error(
        "half.ply",
        &bytes,
        &["header line 8", "unknown property type `half`"],
    );
}

#[test]
fn wrong_property_order() {
    let mut lines = STANDARD.to_vec();
    lines.swap(7, 8);
    let mut bytes = header_text(&lines).into_bytes();
    bytes.extend_from_slice(bytemuck::cast_slice(&sample_points(10)));
    expect_error(
        "order.ply",
        &bytes,
        &[
            "header line 8",
            "expected `property float scalar`, found `property float hp`",
        ],
    );
}

#[test]
fn extra_property_in_a_loudscape_file() {
    let mut lines = STANDARD.to_vec();
    lines.insert(9, "property float extra");
    let mut bytes = header_text(&lines).into_bytes();
    bytes.extend_from_slice(bytemuck::cast_slice(&sample_points(10)));
    expect_error(
        "extra.ply",
        &bytes,
        &["header line 10", "unexpected `property float extra`"],
    );
    // A missing property is as wrong as an extra one.
    let mut lines = STANDARD.to_vec();
    lines.remove(8);
    let bytes = header_text(&lines).into_bytes();
    expect_error(
        "missing_hp.ply",
        &bytes,
        &["header line 9", "missing `property float hp`"],
    );
    // So is a second element.
    let mut lines = STANDARD.to_vec();
    lines.insert(9, "element face 0");
    let bytes = header_text(&lines).into_bytes();
    expect_error(
        "face.ply",
        &bytes,
        &["header line 10", "unexpected `element face`"],
    );
}

#[test]
fn nan_value() {
    let mut bytes = valid_bytes();
    set_value(&mut bytes, 3, 0, f32::NAN);
    let at = header_len(&bytes) + 60;
    expect_error(
        "nan.ply",
        &bytes,
        &[&format!("point 3 at byte {at}"), "x is NaN"],
    );
}

#[test]
fn infinite_value() {
    let mut bytes = valid_bytes();
    set_value(&mut bytes, 5, 3, f32::INFINITY);
    let at = header_len(&bytes) + 5 * 20 + 12;
    expect_error(
        "inf.ply",
        &bytes,
        &[&format!("point 5 at byte {at}"), "scalar is +inf"],
    );
}

#[test]
fn out_of_range_values() {
    let mut bytes = valid_bytes();
    set_value(&mut bytes, 2, 0, 1.5);
    let at = header_len(&bytes) + 40;
    expect_error(
        "x_range.ply",
        &bytes,
        &[
            &format!("point 2 at byte {at}"),
            "x = 1.5 is outside [-1, 1]",
        ],
    );
    let mut bytes = valid_bytes();
    set_value(&mut bytes, 9, 4, -0.25);
    let at = header_len(&bytes) + 9 * 20 + 16;
    expect_error(
        "hp_range.ply",
        &bytes,
        &[
            &format!("point 9 at byte {at}"),
            "hp = -0.25 is outside [0, 1]",
        ],
    );
}

#[test]
fn huge_count_in_a_tiny_file() {
    let mut meta = song_meta();
    meta.as_object_mut().expect("object").remove("point_count");
    let text = header_text(&STANDARD).replace(&song_meta().to_string(), &meta.to_string());
    let huge = text.replace("element vertex 10", "element vertex 4000000000000");
    let started = std::time::Instant::now();
    expect_error(
        "huge.ply",
        huge.as_bytes(),
        &[
            "truncated body",
            "header line 4",
            "4000000000000 points",
            "only 0 bytes",
        ],
    );
    assert!(
        started.elapsed().as_secs_f64() < 1.0,
        "failed slowly: nothing should be allocated"
    );
    // N * 20 overflows 64 bits.
    let overflow = text.replace("element vertex 10", "element vertex 18446744073709551615");
    expect_error(
        "overflow.ply",
        overflow.as_bytes(),
        &["header line 4", "too large"],
    );
    // N does not fit in 64 bits.
    let beyond = text.replace(
        "element vertex 10",
        "element vertex 99999999999999999999999",
    );
    expect_error(
        "beyond.ply",
        beyond.as_bytes(),
        &["header line 4", "not a whole number"],
    );
    // A generic file gets the same protection.
    let generic = "ply\nformat binary_little_endian 1.0\nelement vertex 999999999999\n\
                   property float x\nproperty float y\nproperty float z\nend_header\n";
    expect_error(
        "huge_generic.ply",
        generic.as_bytes(),
        &["truncated body", "header line 3"],
    );
    let generic = generic.replace("binary_little_endian", "ascii");
    expect_error(
        "huge_ascii.ply",
        generic.as_bytes(),
        &["header line 3", "needs at least"],
    );
}

#[test]
fn header_without_end_header() {
    let text = header_text(&STANDARD[..9]);
    expect_error(
        "no_end.ply",
        text.as_bytes(),
        &["header line 10", "ends before `end_header`"],
    );
    // A 10 MB line where the header should end: the file ends first (the cap is 64 MiB).
    let mut bytes = header_text(&STANDARD[..9]).into_bytes();
    bytes.extend(std::iter::repeat_n(b'a', 10 * 1024 * 1024));
    expect_error(
        "long_line.ply",
        &bytes,
        &["header line 10", "ends before `end_header`"],
    );
    // A stream (no length known) of endless header: stops at the cap.
    let endless = std::io::Read::chain(
        std::io::Cursor::new(header_text(&STANDARD[..9]).into_bytes()),
        std::io::repeat(b'a'),
    );
    let err = cloud::load_from_reader(endless, Path::new("endless.ply"), None)
        .expect_err("an endless header fails");
    let message = err.to_string();
    assert!(!message.contains("without"), "{message}");
    assert!(
        message.starts_with("endless.ply: header line 10: ")
            && message.contains("longer than 64 MiB, the most loudscape reads"),
        "{message}"
    );
}

/// A change to a valid meta object that makes it invalid.
type MetaChange = fn(&mut Value);

fn remove(value: &mut Value, key: &str) {
    if let Some(object) = value.as_object_mut() {
        object.remove(key);
    }
}

#[test]
fn bad_json_meta() {
    let bytes = with_header_line(
        3,
        "comment loudscape-meta {\"format_version\": 1, \"mode\": ",
    );
    expect_error(
        "json.ply",
        &bytes,
        &["header line 3", "loudscape-meta: invalid JSON"],
    );
    let cases: [(&str, MetaChange, &str); 7] = [
        (
            "no_version",
            |m| remove(m, "format_version"),
            "missing `format_version`",
        ),
        (
            "version_3",
            |m| m["format_version"] = json!(3),
            "format_version 3 is not supported",
        ),
        ("no_mode", |m| remove(m, "mode"), "missing `mode`"),
        (
            "bad_mode",
            |m| m["mode"] = json!("album"),
            "`mode` must be \"song\" or \"timeline\", found \"album\"",
        ),
        ("no_axes", |m| remove(m, "axes"), "missing `axes`"),
        (
            "no_hp_axis",
            |m| remove(&mut m["axes"], "hp"),
            "`axes` has no `hp` axis",
        ),
        (
            "log_zero",
            |m| m["axes"]["y"]["min"] = json!(0.0),
            "`axes.y`: a log axis needs positive min and max",
        ),
    ];
    for (name, change, needle) in cases {
        let mut meta = song_meta();
        change(&mut meta);
        // Written by hand: the writer owns `format_version` and would set it.
        let bytes = with_header_line(3, &format!("comment loudscape-meta {meta}"));
        expect_error(&format!("{name}.ply"), &bytes, &["header line 3", needle]);
    }
    let mut meta = song_meta();
    meta["axes"]["x"]["min"] = json!("zero");
    expect_error(
        "axis_type.ply",
        &file_bytes(&sample_points(10), &meta),
        &["header line 3", "`axes.x`"],
    );
    let mut meta = song_meta();
    meta["metrics"]["plr_db"] = json!("loud");
    expect_error(
        "metric_type.ply",
        &file_bytes(&sample_points(10), &meta),
        &["header line 3", "`metrics`"],
    );
}

#[test]
fn empty_file() {
    expect_error("empty.ply", b"", &["header line 1", "empty"]);
}

#[test]
fn non_utf8_header() {
    let bytes = with_header_line(3, "comment caf\u{e9}");
    let mut bytes = bytes;
    let at = bytes.iter().position(|&b| b == 0xc3).expect("the e acute");
    bytes[at] = 0xff;
    expect_error("utf8.ply", &bytes, &["header line 3", "not valid UTF-8"]);
}

#[test]
fn other_header_mistakes() {
    let bytes = with_header_line(5, "propertyfloat x");
    expect_error(
        "keyword.ply",
        &bytes,
        &["header line 5", "unknown header keyword"],
    );
    let mut lines = STANDARD.to_vec();
    lines.remove(1);
    expect_error(
        "no_format.ply",
        header_text(&lines).as_bytes(),
        &["header line 9", "no `format` line"],
    );
    let generic = "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\n\
                   property float y\nproperty float z\nend_header\n\0\0\0\0\0\0\0\0\0\0\0\0";
    expect_error(
        "generic_big_endian.ply",
        generic.as_bytes(),
        &["header line 2", "binary_big_endian PLY is not supported"],
    );
    let no_z = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n";
    expect_error(
        "no_z.ply",
        no_z.as_bytes(),
        &["header line 3", "no property `z`"],
    );
    let words = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                 property float z\nend_header\n1 2 3\n1 two 3\n";
    let second_line = header_len(words.as_bytes()) + "1 2 3\n".len();
    expect_error(
        "ascii_word.ply",
        words.as_bytes(),
        &[
            &format!("byte {second_line}"),
            "line 9",
            "`two` is not a number",
        ],
    );
    let short = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                 property float z\nend_header\n1.0 2.0 3.0\n4.0 5.0 6.0\n";
    expect_error(
        "ascii_short.ply",
        short.as_bytes(),
        &["ends after 2 of 3 vertex records"],
    );
    let nan = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
               property float z\nend_header\n1 2 3\n1 nan 3\n";
    expect_error(
        "ascii_nan.ply",
        nan.as_bytes(),
        &[
            &format!("point 1 at byte {second_line}"),
            "line 9",
            "y is NaN",
        ],
    );
    let dir = scratch_dir();
    let err = cloud::load(&dir).expect_err("a directory is not a file");
    assert!(
        err.to_string().starts_with(&dir.display().to_string()),
        "{err}"
    );
    let missing = dir.join("does_not_exist.ply");
    let err = cloud::load(&missing).expect_err("missing file");
    assert!(
        err.to_string().contains("does_not_exist.ply: cannot open"),
        "{err}"
    );
}
