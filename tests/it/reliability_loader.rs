//! Never a silent wrong result, the loader side: a generic PLY that holds more points than it
//! declares, an ascii PLY cut inside its last number, a header over the cap that has its
//! `end_header`, deeply nested JSON and malformed `warnings`: each one line naming the file, the
//! place and the reason. And a cloud's `warnings` come back from the file.

use std::path::Path;

use loudscape::data::cloud;
use serde_json::json;

use crate::loader_files::*;

const GENERIC_ASCII: &str = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n\
                             property float y\nproperty float z\nend_header\n";

#[test]
fn a_generic_file_with_more_points_than_declared_is_refused() {
    // ascii: a third record after the two declared (trailing blank lines are fine).
    let fine = format!("{GENERIC_ASCII}0 0 0\n1 1 1\n\n  \n");
    assert_eq!(
        cloud::load(&write_file("two.ply", fine.as_bytes()))
            .unwrap()
            .len(),
        2
    );
    let more = format!("{GENERIC_ASCII}0 0 0\n1 1 1\n2 2 2\n");
    let at = (GENERIC_ASCII.len() + 12).to_string();
    expect_error(
        "more_ascii.ply",
        more.as_bytes(),
        &[
            &format!("byte {at}"),
            "data follows the last of the 2 points",
            "header line 3",
        ],
    );
    // binary little endian: one record more than declared.
    let header = "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n\
                  property float y\nproperty float z\nend_header\n";
    let mut bytes = header.as_bytes().to_vec();
    for v in [0f32, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let at = (header.len() + 24).to_string();
    expect_error(
        "more_binary.ply",
        &bytes,
        &[
            &format!("byte {at}"),
            "data follows the last of the 2 points",
        ],
    );
    // Through a stream of unknown length too.
    let err = cloud::load_from_reader(bytes.as_slice(), Path::new("s.ply"), None).unwrap_err();
    assert!(err.to_string().contains("data follows"), "{err}");
    // A later element (faces) is not "more points".
    let with_faces = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                      property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                      end_header\n0 0 0\n1 1 1\n2 0 1\n";
    assert_eq!(
        cloud::load(&write_file("faces.ply", with_faces.as_bytes()))
            .unwrap()
            .len(),
        2
    );
}

#[test]
fn an_ascii_file_cut_inside_its_last_number_is_refused() {
    // "1.25" cut to "1.2": still a number, but the line break every record ends with is gone.
    let cut = format!("{GENERIC_ASCII}0 0 0\n1 1 1.2");
    expect_error(
        "cut.ply",
        cut.as_bytes(),
        &["line 9", "ends inside vertex record 1", "cut short"],
    );
}

#[test]
fn a_header_over_the_cap_is_called_too_large_even_with_its_end_header() {
    let mut bytes = b"ply\nformat binary_little_endian 1.0\ncomment ".to_vec();
    bytes.extend(std::iter::repeat_n(b'a', 65 << 20));
    bytes.extend_from_slice(b"\nelement vertex 0\nproperty float x\nend_header\n");
    let err = expect_error("huge_header.ply", &bytes, &["longer than 64 MiB"]);
    assert!(!err.to_string().contains("without"), "{err}");
}

#[test]
fn deeply_nested_json_is_named_as_such() {
    let mut meta = song_meta();
    let mut deep = json!(1);
    for _ in 0..200 {
        deep = json!([deep]);
    }
    meta["deep"] = deep;
    expect_error(
        "deep.ply",
        &file_bytes(&sample_points(10), &meta),
        &["nests deeper than 128 levels"],
    );
}

#[test]
fn warnings_are_read_and_malformed_ones_refused() {
    let mut meta = song_meta();
    meta["warnings"] = json!([
        {"kind": "truncated", "message": "decoded 1.49 s of the 4.00 s the file promises"},
        {"kind": "dc_offset", "message": "DC offset 0.120 of full scale"}
    ]);
    let path = write_file("warned.ply", &file_bytes(&sample_points(10), &meta));
    let loaded = cloud::load(&path).unwrap();
    assert_eq!(loaded.warnings().len(), 2);
    assert_eq!(loaded.warnings()[0].kind, "truncated");
    assert_eq!(
        loaded.warning_lines()[1],
        format!("warning: {}: DC offset 0.120 of full scale", path.display())
    );
    // Timeline warnings name their song.
    meta["warnings"] = json!([{"kind": "clipping", "message": "clips", "path": "b.wav"}]);
    let path = write_file("warned2.ply", &file_bytes(&sample_points(10), &meta));
    assert_eq!(
        cloud::load(&path).unwrap().warning_lines(),
        ["warning: b.wav: clips"]
    );
    assert!(
        cloud::load(&write_file("none.ply", &valid_bytes()))
            .unwrap()
            .warnings()
            .is_empty()
    );
    meta["warnings"] = json!("disk on fire");
    expect_error(
        "bad_warnings.ply",
        &file_bytes(&sample_points(10), &meta),
        &["loudscape-meta", "`warnings` must be an array"],
    );
}
