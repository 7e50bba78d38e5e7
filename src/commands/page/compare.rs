//! `loudscape page A --compare B -o ab.html`: the page of an A/B compare, A and B side by side
//! in the browser as in the window's Compare view (src/web/compare.rs).
//!
//! B is moved onto A's time and loudness as `render --compare` moves it (`--align`, `--offset`,
//! `--match-loudness`: [`super::super::compare_align::align_b_as`]), then both clouds go onto
//! the union of their axes (`data::compare::on_union_axes`), so equal loudness looks equal in
//! both halves. The page's point budget is split between the two ([`split_budget`]), each is
//! thinned and quantized as a song's page is (`data::page_cloud`), and the page's note says what
//! was thinned of each ([`compare_note`]).

use anyhow::bail;
use loudscape::data::cloud::{DataMode, PointCloud};
use loudscape::data::compare::on_union_axes;
use loudscape::data::page_cloud::{self, Thinning};

/// What the page of a compare carries of A and B.
pub struct ComparePage {
    /// A's and B's page data (`data::page_cloud`), on the union of their axes.
    pub data: [Vec<u8>; 2],
    pub thinning: [Thinning; 2],
    /// Each half's label: "A: name", "B: name, +0.42 s, -1.3 dB".
    pub labels: [String; 2],
    /// What was thinned of each.
    pub note: String,
}

/// Refuses a compare of anything but two songs: a timeline's page shows one timeline.
pub fn check_songs(a: &PointCloud, b: &PointCloud) -> anyhow::Result<()> {
    for cloud in [a, b] {
        if cloud.meta.mode == DataMode::Timeline {
            bail!(
                "{}: --compare is for two songs, and this is a timeline",
                cloud.path.display()
            );
        }
    }
    Ok(())
}

/// `max_points` split between A (`len_a` points) and B (`len_b`): half each, and what one of
/// them cannot use goes to the other; each gets at least one.
pub fn split_budget(len_a: usize, len_b: usize, max_points: usize) -> (usize, usize) {
    let half = max_points / 2;
    let a = len_a.min(half.max(max_points.saturating_sub(len_b))).max(1);
    let b = len_b.min(max_points.saturating_sub(a)).max(1);
    (a, b)
}

/// B's half's label: its name and how it was moved onto A ("B: name, +0.42 s, -1.3 dB").
pub fn label_b(name: &str, offset_s: Option<f64>, gain_db: Option<f64>) -> String {
    let mut label = format!("B: {name}");
    if let Some(offset) = offset_s {
        label.push_str(&format!(", {offset:+.2} s"));
    }
    if let Some(gain) = gain_db {
        label.push_str(&format!(", {gain:+.1} dB"));
    }
    label
}

/// The page's note: what it carries of A and of B.
pub fn compare_note(thinning: &[Thinning; 2]) -> String {
    let part = |which: &str, t: &Thinning| {
        if t.stride > 1 {
            format!(
                "{which}: {} of its {} points (every {})",
                t.kept,
                t.total,
                super::ordinal(t.stride)
            )
        } else {
            format!("{which}: every point")
        }
    };
    format!(
        "This page carries {}; {}; positions to 1/65535 of the box.",
        part("A", &thinning[0]),
        part("B", &thinning[1])
    )
}

/// A and B (B already moved onto A's time and loudness, `offset_s` and `gain_db` saying how) on
/// their union axes, thinned into `max_points` together, named `names` on the page.
pub fn compare_page(
    a: &PointCloud,
    b: &PointCloud,
    names: [&str; 2],
    offset_s: Option<f64>,
    gain_db: Option<f64>,
    max_points: usize,
) -> anyhow::Result<ComparePage> {
    check_songs(a, b)?;
    let (a, b) = on_union_axes(a, b).map_err(|e| anyhow::anyhow!("{e}"))?;
    let (max_a, max_b) = split_budget(a.len(), b.len(), max_points);
    let (data_a, thinning_a) = page_cloud::encode(&a, max_a);
    let (data_b, thinning_b) = page_cloud::encode(&b, max_b);
    let thinning = [thinning_a, thinning_b];
    Ok(ComparePage {
        data: [data_a, data_b],
        note: compare_note(&thinning),
        thinning,
        labels: [
            format!("A: {}", names[0]),
            label_b(names[1], offset_s, gain_db),
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use loudscape::data::cloud;

    fn demo() -> PointCloud {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/data/demo_song.ply");
        let bytes = std::fs::read(path).expect("demo song");
        cloud::load_from_bytes(&bytes, std::path::Path::new("demo_song.ply")).expect("loads")
    }

    /// B: the demo 6 dB louder and 0.5 s later (its level, loudness and time axes moved).
    fn louder_and_later(a: &PointCloud) -> PointCloud {
        let mut b = a.clone();
        b.path = "louder.ply".into();
        for axis in [&mut b.meta.axes.y, &mut b.meta.axes.scalar] {
            axis.min += 6.0;
            axis.max += 6.0;
        }
        b.meta.axes.x.min += 0.5;
        b.meta.axes.x.max += 0.5;
        b
    }

    /// Both clouds in the page, on one set of axes (the union of both), each thinned into its
    /// share of the budget, and the note and the labels saying so.
    #[test]
    fn both_clouds_go_in_on_their_union_axes_within_the_budget() {
        let a = demo();
        let b = louder_and_later(&a);
        let budget = a.len(); // room for half of each
        let page = compare_page(
            &a,
            &b,
            ["demo_song.ply", "louder.ply"],
            Some(0.42),
            Some(-1.3),
            budget,
        )
        .expect("a page");
        let back: Vec<PointCloud> = page
            .data
            .iter()
            .map(|d| page_cloud::decode(d, "x").expect("decodes"))
            .collect();
        let union = loudscape::data::compare::union_axes(&a, &b).expect("union");
        assert_eq!(back[0].meta.axes, union);
        assert_eq!(back[1].meta.axes, union);
        // The union's level axis reaches 6 dB above A's: B's points sit higher than A's.
        assert!((union.y.max - a.meta.axes.y.max - 6.0).abs() < 1e-9);
        let mean_y = |c: &PointCloud| {
            c.points
                .iter()
                .map(|p| f64::from(p.position[1]))
                .sum::<f64>()
                / c.len() as f64
        };
        assert!(mean_y(&back[1]) > mean_y(&back[0]) + 0.05);
        assert_eq!(back[0].len() + back[1].len(), budget);
        assert_eq!(page.thinning[0].kept, back[0].len());
        assert_eq!(page.thinning[1].kept, back[1].len());
        assert_eq!(page.thinning[0].stride, 2);
        assert_eq!(
            page.note,
            format!(
                "This page carries A: {} of its {} points (every 2nd); B: {} of its {} points \
                 (every 2nd); positions to 1/65535 of the box.",
                back[0].len(),
                a.len(),
                back[1].len(),
                b.len()
            )
        );
        assert_eq!(
            page.labels,
            ["A: demo_song.ply", "B: louder.ply, +0.42 s, -1.3 dB"]
        );
    }

    #[test]
    fn the_budget_is_split_and_what_one_cannot_use_goes_to_the_other() {
        assert_eq!(split_budget(100, 100, 100), (50, 50));
        assert_eq!(split_budget(10, 1000, 100), (10, 90));
        assert_eq!(split_budget(1000, 10, 100), (90, 10));
        assert_eq!(split_budget(10, 10, 100), (10, 10));
        assert_eq!(split_budget(5, 5, 1), (1, 1));
        let whole = [
            Thinning {
                total: 7,
                kept: 7,
                stride: 1,
            },
            Thinning {
                total: 9,
                kept: 3,
                stride: 3,
            },
        ];
        assert_eq!(
            compare_note(&whole),
            "This page carries A: every point; B: 3 of its 9 points (every 3rd); positions to \
             1/65535 of the box."
        );
        assert_eq!(label_b("b.flac", None, None), "B: b.flac");
    }

    #[test]
    fn a_timeline_is_refused_on_either_side() {
        let song = demo();
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/data/demo_timeline.ply");
        let bytes = std::fs::read(path).expect("demo timeline");
        let timeline =
            cloud::load_from_bytes(&bytes, std::path::Path::new("demo_timeline.ply")).unwrap();
        for (a, b) in [(&song, &timeline), (&timeline, &song)] {
            let error = compare_page(a, b, ["a", "b"], None, None, 1000)
                .err()
                .expect("refused")
                .to_string();
            assert_eq!(
                error,
                "demo_timeline.ply: --compare is for two songs, and this is a timeline"
            );
        }
    }
}
