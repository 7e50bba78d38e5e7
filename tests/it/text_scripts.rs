//! Text in other scripts and directions in a whole `loudscape render`: a song whose name is
//! Hebrew with a year ("שלום 2020 (2000)") was drawn "(0002) 0202" and four empty boxes. The
//! picture's name is found where the legend puts it, and no letter of it may be the empty box.

use std::io::BufWriter;
use std::path::Path;

use loudscape::annotate::raster;
use loudscape::annotate::{Anchor, Annotation, Text, font, legend};
use loudscape::data::cloud;

use crate::common::{self, assert_success, loudscape};

/// The demo song's points and metadata, its source renamed `source_name`, written to `path`.
fn demo_named(source_name: &str, path: &Path) {
    let demo = common::demo_song();
    let mut meta = demo.meta.raw.clone();
    meta["source"]["path"] = serde_json::Value::from(source_name);
    let file = std::fs::File::create(path).expect("create the cloud");
    let mut writer = BufWriter::new(file);
    cloud::write(&mut writer, &demo.points, Some(&meta)).expect("write the cloud");
}

/// Which pixels of `image` inside `[x0, x1) x [y0, y1)` are ink: brighter than `background`'s
/// brightest channel by more than 80.
fn ink_mask(image: &image::RgbaImage, x0: u32, y0: u32, x1: u32, y1: u32) -> Vec<Vec<bool>> {
    let background = image.get_pixel(image.width() - 2, image.height() - 2);
    let level = |p: &image::Rgba<u8>| p[0].max(p[1]).max(p[2]);
    let floor = level(background).saturating_add(80);
    (y0..y1)
        .map(|y| {
            (x0..x1)
                .map(|x| level(image.get_pixel(x, y)) > floor)
                .collect()
        })
        .collect()
}

/// The ink of the empty box alone at `size`, cropped to its ink.
fn empty_box_mask(size: f32) -> Vec<Vec<bool>> {
    let mut image = image::RgbaImage::from_pixel(64, 64, image::Rgba([0, 0, 0, 255]));
    let mut shapes = Annotation::default();
    shapes.text(Text::new(
        "\u{10FFFD}",
        [8.0, 8.0],
        Anchor::LEFT_TOP,
        size,
        [255; 4],
    ));
    raster::draw(&mut image, &shapes.shapes, 1.0);
    let mask = ink_mask(&image, 0, 0, 64, 64);
    let rows: Vec<usize> = (0..64).filter(|y| mask[*y].iter().any(|i| *i)).collect();
    let cols: Vec<usize> = (0..64).filter(|x| mask.iter().any(|row| row[*x])).collect();
    let (r0, r1, c0, c1) = (rows[0], rows[rows.len() - 1], cols[0], cols[cols.len() - 1]);
    mask[r0..=r1]
        .iter()
        .map(|row| row[c0..=c1].to_vec())
        .collect()
}

/// Where in `region` the `template` matches with at most a tenth of its pixels different.
fn matches(region: &[Vec<bool>], template: &[Vec<bool>]) -> Vec<(usize, usize)> {
    let (th, tw) = (template.len(), template[0].len());
    let mut found = Vec::new();
    for y in 0..region.len().saturating_sub(th) {
        for x in 0..region[0].len().saturating_sub(tw) {
            let differing: usize = (0..th)
                .map(|j| {
                    (0..tw)
                        .filter(|i| region[y + j][x + i] != template[j][*i])
                        .count()
                })
                .sum();
            if differing * 10 <= th * tw {
                found.push((x, y));
            }
        }
    }
    found
}

#[test]
fn a_hebrew_song_name_renders_as_letters_in_reading_order() {
    let dir = common::fresh_dir("text_scripts");
    let title = "שלום 2020 (2000).flac";
    let path = dir.join("hebrew.ply");
    demo_named(title, &path);
    assert_eq!(
        legend::picture_name(&cloud::load(&path).expect("load")),
        title
    );
    let out = dir.join("hebrew.png");
    let output = loudscape(&[
        "render".as_ref(),
        path.as_os_str(),
        "--size".as_ref(),
        "640x360".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_success(&output);
    let image = image::open(&out).expect("the picture").to_rgba8();

    // The name's box, as the legend lays it out (top left, 16 points, one pixel a point).
    let [width, height] = font::measure(title, 16.0);
    let (x0, y0) = (legend::MARGIN as u32, legend::MARGIN as u32);
    let (x1, y1) = (x0 + width.ceil() as u32 + 2, y0 + height.ceil() as u32 + 2);
    let region = ink_mask(&image, x0, y0, x1, y1);
    let inked = region.iter().flatten().filter(|i| **i).count();
    assert!(inked > 150, "the name has {inked} pixels of ink");

    // The empty box is found where it is drawn (the test can see one) ...
    let empty_box = empty_box_mask(16.0);
    let mut boxed = image::RgbaImage::from_pixel(200, 40, image::Rgba([0, 0, 0, 255]));
    let mut shapes = Annotation::default();
    shapes.text(Text::new(
        "ab \u{10FFFD}",
        [3.0, 5.0],
        Anchor::LEFT_TOP,
        16.0,
        [255; 4],
    ));
    raster::draw(&mut boxed, &shapes.shapes, 1.0);
    assert_eq!(
        matches(&ink_mask(&boxed, 0, 0, 200, 40), &empty_box).len(),
        1
    );
    // ... and nowhere in the name.
    let found = matches(&region, &empty_box);
    assert!(
        found.is_empty(),
        "empty boxes in the name at {found:?} (see {})",
        out.display()
    );
}
