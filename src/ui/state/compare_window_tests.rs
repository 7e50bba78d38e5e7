//! The unit tests of `state/compare_window.rs`: what the compare's state decides by itself
//! (loads, versions added and dropped, key B's order, the scene and grids, the dialog).

use std::sync::mpsc::channel;

use super::*;
use crate::data::cloud::DataMode;
use crate::render::compare::BuiltGrids;

fn cloud(points: usize) -> PointCloud {
    PointCloud::synthetic(
        crate::data::synthetic::synthetic_song(points, 7),
        DataMode::Song,
    )
}

fn loading(
    path: &str,
) -> (
    CompareState,
    std::sync::mpsc::Sender<Result<PointCloud, String>>,
) {
    let mut state = CompareState::new(PathBuf::from(path));
    let (sender, receiver) = channel();
    state.versions[0].receiver = Some(receiver);
    (state, sender)
}

/// A version being loaded is added to `state` (C after B...).
fn adding(
    state: &mut CompareState,
    path: &str,
) -> std::sync::mpsc::Sender<Result<PointCloud, String>> {
    let added = state.add(PathBuf::from(path)).unwrap();
    let (sender, receiver) = channel();
    state.versions[added.0 - 1].receiver = Some(receiver);
    sender
}

#[test]
fn a_finished_load_leaves_b_and_asks_for_a_new_scene() {
    let (mut state, sender) = loading("b.ply");
    state.built_for = Some((3, Listening::B, false));
    assert_eq!(state.poll_load(), (true, vec![]), "nothing sent yet");
    assert!(state.loading());
    sender.send(Ok(cloud(50))).unwrap();
    assert_eq!(state.poll_load(), (false, vec![Listening::B]));
    assert!(!state.loading());
    assert_eq!(state.beside_loaded().map(|b| b.len()), Some(50));
    assert_eq!(
        state.built_for, None,
        "the scene is built again for the new B"
    );
    assert_eq!(state.error, None);
    assert_eq!(state.poll_load(), (false, vec![]), "nothing more to take");
}

/// More versions: each added is shown beside A while A is heard, a file already
/// compared is not added twice, at most eight in all, and one that does not load leaves
/// the list (the later ones move up a letter).
#[test]
fn versions_are_added_up_to_eight_and_one_that_fails_leaves() {
    let (mut state, b) = loading("b.ply");
    let c = adding(&mut state, "c.ply");
    assert_eq!(state.count(), 3);
    assert_eq!(state.beside, Listening::B, "B beside A");
    state.show(Listening(2));
    assert_eq!(
        state.beside,
        Listening(2),
        "the version added by hand is seen"
    );
    let error = state.add(PathBuf::from("b.ply")).unwrap_err();
    assert!(error.contains("already compared (as B)"), "{error}");
    let d = adding(&mut state, "d.ply");
    b.send(Err("b.ply: not a loudscape cloud".into())).unwrap();
    c.send(Ok(cloud(20))).unwrap();
    assert_eq!(state.poll_load(), (true, vec![Listening::B]), "C is B now");
    assert_eq!(state.error.as_deref(), Some("b.ply: not a loudscape cloud"));
    assert_eq!(state.count(), 3);
    assert_eq!(state.versions[0].path, PathBuf::from("c.ply"));
    assert_eq!(state.beside, Listening::B, "still C, as B now");
    d.send(Ok(cloud(30))).unwrap();
    assert_eq!(state.poll_load(), (false, vec![Listening(2)]));
    assert_eq!(state.beside_loaded().map(|v| v.len()), Some(20));
    state.show(Listening(2));
    assert_eq!(state.beside_loaded().map(|v| v.len()), Some(30));
    for name in ["e", "f", "g", "h", "i"] {
        state.add(PathBuf::from(format!("{name}.ply"))).unwrap();
    }
    assert_eq!(state.count(), MAX_VERSIONS);
    let error = state.add(PathBuf::from("j.ply")).unwrap_err();
    assert!(error.contains("at most 8 versions"), "{error}");
}

/// Key B steps A -> B -> C -> A through the versions whose audio is decoded, and each
/// waits in its own slot while another plays.
#[test]
fn key_b_steps_through_the_decoded_versions() {
    let mut state = CompareState::new(PathBuf::from("b.ply"));
    state.add(PathBuf::from("c.ply")).unwrap();
    assert_eq!(state.next_heard(), None, "nothing decoded yet");
    let demo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.flac");
    let track = || crate::playback::decode(&demo).unwrap();
    *state.track_slot(Listening(2)).unwrap() = Some(track());
    assert_eq!(state.next_heard(), Some(Listening(2)), "B not decoded: C");
    *state.track_slot(Listening::B).unwrap() = Some(track());
    assert_eq!(state.next_heard(), Some(Listening::B));
    // B plays (the player took its track), A's waits.
    let playing = state.track_slot(Listening::B).unwrap().take();
    state.a_track = Some(track());
    state.listening = Listening::B;
    assert_eq!(state.next_heard(), Some(Listening(2)));
    // C plays, B's waits: after C comes A.
    state.track_slot(Listening(2)).unwrap().take();
    *state.track_slot(Listening::B).unwrap() = playing;
    state.listening = Listening(2);
    assert_eq!(state.next_heard(), Some(Listening::A), "after C comes A");
    state.a_track = None;
    assert_eq!(state.next_heard(), Some(Listening::B), "A not there: B");
    state.track_slot(Listening::B).unwrap().take();
    assert_eq!(state.next_heard(), None, "none waits");
    assert!(state.track_slot(Listening(3)).is_none());
}

/// B's warnings (truncated, clipped...) are told as A's are, naming the file asked for
/// (for audio B's cloud is a cache file of no meaning to the user).
#[test]
fn bs_warnings_are_told_by_the_name_it_was_asked_by() {
    let (mut state, sender) = loading("/music/b_louder.ogg");
    assert!(
        state.warning_lines(Listening::B).is_empty(),
        "nothing loaded yet"
    );
    let mut b = cloud(50);
    b.meta.warnings.push(crate::data::cloud::CloudWarning {
        kind: "clipping".into(),
        message: "clipped: 3 run(s)".into(),
        path: None,
    });
    sender.send(Ok(b)).unwrap();
    assert!(!state.poll_load().0);
    assert_eq!(
        state.warning_lines(Listening::B),
        ["B b_louder.ogg: clipped: 3 run(s)"]
    );
}

#[test]
fn a_failed_or_abandoned_load_leaves_an_error_that_is_told_once() {
    let (mut state, sender) = loading("b.ply");
    sender
        .send(Err("b.ply: not a loudscape cloud".into()))
        .unwrap();
    assert!(!state.poll_load().0);
    assert!(state.is_empty(), "B failed: nothing to compare");
    assert_eq!(
        state.error_to_tell().as_deref(),
        Some("b.ply: not a loudscape cloud")
    );
    assert_eq!(state.error_to_tell(), None, "told once");

    let (mut state, sender) = loading("gone.ogg");
    drop(sender);
    assert!(!state.poll_load().0);
    assert_eq!(
        state.error.as_deref(),
        Some("gone.ogg: the loader stopped"),
        "a loader that died names the file"
    );
    state.error = Some("another".into());
    assert_eq!(state.error_to_tell().as_deref(), Some("another"));
    state.error = None;
    assert_eq!(state.error_to_tell(), None, "no error has nothing to tell");
}

#[test]
fn failed_audio_is_an_error_and_a_dropped_decoder_only_stops_waiting() {
    let mut state = CompareState::new(PathBuf::from("b.ogg"));
    let (sender, receiver) = channel();
    state.versions[0].decoding = Some(receiver);
    assert!(state.poll_decoding());
    sender
        .send(Err(PlaybackError::Open {
            path: PathBuf::from("b.ogg"),
            reason: "truncated".into(),
        }))
        .unwrap();
    assert!(!state.poll_decoding());
    assert!(state.versions[0].decoding.is_none() && state.versions[0].track.is_none());
    let error = state.error.clone().unwrap_or_default();
    assert!(
        error.starts_with("B's audio: b.ogg") && error.contains("truncated"),
        "{error}"
    );

    let mut state = CompareState::new(PathBuf::from("b.ogg"));
    let (sender, receiver) = channel::<Result<Track, PlaybackError>>();
    state.versions[0].decoding = Some(receiver);
    drop(sender);
    assert!(!state.poll_decoding());
    assert!(state.versions[0].decoding.is_none() && state.error.is_none());
}

#[test]
fn a_version_added_keeps_the_measure_and_is_shown() {
    let fresh = CompareState::new(PathBuf::from("b.ply"));
    assert_eq!(fresh.layout, CompareLayout::SideBySide);
    assert_eq!(fresh.measure, DifferenceMeasure::Density);
    assert_eq!(fresh.versions[0].path, PathBuf::from("b.ply"));

    let mut old = CompareState::new(PathBuf::from("old.ply"));
    old.layout = CompareLayout::Off;
    old.measure = DifferenceMeasure::ALL[1];
    old.add(PathBuf::from("c.ply")).unwrap();
    assert_eq!(
        old.layout,
        CompareLayout::SideBySide,
        "A only turns to the version beside it"
    );
    assert_eq!(old.measure, DifferenceMeasure::ALL[1]);
    old.layout = CompareLayout::Difference;
    old.listening = Listening::B;
    old.beside = Listening::B;
    let d = old.add(PathBuf::from("d.ply")).unwrap();
    old.show(d);
    assert_eq!(old.layout, CompareLayout::Difference);
    assert_eq!(old.beside, Listening::B, "beside A: the version heard");
}

#[test]
fn the_scene_is_built_once_per_song_and_the_grids_only_where_drawn() {
    let mut state = CompareState::new(PathBuf::from("b.ply"));
    assert!(
        !state.needs_grids(ViewKind::Volume),
        "nothing to compare yet"
    );
    assert!(!state.shown() && !state.side_by_side());
    state.clouds = Some(Arc::new((cloud(10), cloud(12))));
    assert!(state.rebuild_for(1));
    assert!(!state.rebuild_for(1), "built for this song already");
    assert!(state.rebuild_for(2), "another song in A");
    let c = state.add(PathBuf::from("c.ply")).unwrap();
    assert!(!state.rebuild_for(2), "B still beside A");
    state.show(c);
    assert!(state.rebuild_for(2), "another version beside A");
    assert!(!state.rebuild_for(2));

    assert!(state.shown() && state.side_by_side());
    assert!(!state.needs_grids(ViewKind::Points));
    assert!(state.needs_grids(ViewKind::Volume));
    assert!(state.needs_grids(ViewKind::Surface));
    state.layout = CompareLayout::Difference;
    assert!(state.needs_grids(ViewKind::Points));
    assert!(state.shown() && !state.side_by_side());
    state.layout = CompareLayout::Off;
    assert!(!state.needs_grids(ViewKind::Volume));
    assert!(!state.shown());
}

#[test]
fn grids_are_built_once_per_settings_and_a_failure_is_not_retried() {
    let mut state = CompareState::new(PathBuf::from("b.ply"));
    let voxels = VoxelSettings::default();
    assert_eq!(state.grid_step(&voxels, true), GridStep::Ready);
    assert_eq!(state.grid_step(&voxels, false), GridStep::Start);
    let (sender, receiver) = channel();
    state.building(voxels, receiver);
    assert!(state.grids_building());
    assert_eq!(state.grid_step(&voxels, false), GridStep::Wait);
    assert_eq!(state.grid_step(&voxels, false), GridStep::Wait);
    assert!(state.poll_grid_build().is_none(), "nothing sent yet");
    assert_eq!(state.grid_build.as_ref().map(|b| b.frames), Some(2));
    sender
        .send(Err("b.ply: voxelizing: too large".into()))
        .unwrap();
    assert!(state.poll_grid_build().is_none());
    assert!(!state.grids_building());
    assert_eq!(state.error.as_deref(), Some("b.ply: voxelizing: too large"));
    assert_eq!(
        state.grid_step(&voxels, false),
        GridStep::Failed,
        "not started again every frame"
    );
    let mut other = voxels;
    other.smoothing_sigma = Some(other.smoothing_for(crate::data::cloud::DataMode::Song) + 0.5);
    assert_eq!(state.grid_step(&other, false), GridStep::Start);

    // A build for other settings is dropped; a thread that died is an error.
    let (sender, receiver) = channel();
    state.building(voxels, receiver);
    assert_eq!(state.grid_step(&other, false), GridStep::Start);
    assert!(!state.grids_building());
    drop(sender);
    let (sender, receiver) = channel::<Result<BuiltGrids, String>>();
    state.building(other, receiver);
    drop(sender);
    assert!(state.poll_grid_build().is_none());
    assert!(
        state
            .error
            .as_deref()
            .is_some_and(|e| e.contains("stopped")),
        "{:?}",
        state.error
    );

    // A new scene drops the build of the old one.
    let (_sender, receiver) = channel();
    state.building(voxels, receiver);
    assert!(state.rebuild_for(9));
    assert!(!state.grids_building());
}

#[test]
fn the_difference_copy_is_read_again_for_another_measure() {
    let mut state = CompareState::new(PathBuf::from("b.ply"));
    assert!(state.difference_stale(), "none read yet");
    state.difference = Some(DifferenceCopy {
        shown: Field {
            dims: glam::UVec3::ONE,
            box_min: glam::Vec3::ZERO,
            box_max: glam::Vec3::ONE,
            density: vec![0.0],
            hp_mean: vec![0.0],
        },
        difference: vec![0.0],
        columns: vec![0.0],
        measure: state.measure,
        range: 1.0,
    });
    assert!(!state.difference_stale());
    state.measure = DifferenceMeasure::ALL[1];
    assert!(state.difference_stale());
    state.measure = DifferenceMeasure::ALL[0];
    state.built_for = Some((1, Listening::B, false));
    assert!(state.rebuild_for(2));
    assert!(
        state.difference_stale(),
        "a new scene drops the old difference"
    );
}

#[test]
fn the_panel_starts_b_from_the_field_or_the_dialog() {
    assert_eq!(typed_path("  b.ogg ", true), Some(PathBuf::from("b.ogg")));
    assert_eq!(typed_path("b.ogg", false), None, "only on Enter");
    assert_eq!(typed_path("   ", true), None, "nothing typed");

    let mut state = CompareState::empty();
    assert_eq!(state.poll_dialog(), Poll::Ready(vec![]), "no dialog");
    let (sender, receiver) = channel();
    state.await_dialog(receiver);
    assert_eq!(state.layout, CompareLayout::Off, "A alone while picking");
    assert_eq!(state.poll_dialog(), Poll::Pending);
    sender
        .send(Some(vec![PathBuf::from("b.ply"), PathBuf::from("c.ply")]))
        .unwrap();
    assert_eq!(
        state.poll_dialog(),
        Poll::Ready(vec![PathBuf::from("b.ply"), PathBuf::from("c.ply")]),
        "each file picked is a version"
    );
    assert!(state.dialog.is_none());

    let (sender, receiver) = channel();
    state.await_dialog(receiver);
    sender.send(None).unwrap();
    assert_eq!(state.poll_dialog(), Poll::Ready(vec![]), "cancelled");
}

#[test]
fn the_panel_switches_sides_only_to_decoded_audio() {
    let state = CompareState::new(PathBuf::from("b.ply"));
    assert!(state.can_listen(Listening::A), "the side heard");
    assert!(!state.can_listen(Listening::B), "B's audio not decoded");
    assert_eq!(Listening::A.next(2), Listening::B);
    assert_eq!(Listening::B.next(2), Listening::A);
}

/// The "matched" measure is level-weighted, shows only in the difference and only once the
/// comparison has the gains, and the scene is built again when it starts or stops showing.
#[test]
fn the_matched_measure_rebuilds_the_difference_once_there_are_gains() {
    let mut state = CompareState::new(PathBuf::from("b.ply"));
    state.layout = CompareLayout::Difference;
    assert!(state.rebuild_for(1));
    state.pick_measure(None);
    assert!(state.matched && state.measure == DifferenceMeasure::ALL[1]);
    assert!(!state.matched_shown(), "no gains yet");
    assert!(!state.rebuild_for(1));
    state.alignment.comparison = Some(
        crate::extract::align::Comparison::parse(
            r#"{"match": "quietest", "versions": [
            {"path": "a.wav", "match_gain_db": 0.0, "alignment": {"alignable": true,
             "offset_s": 0.0, "confidence": 1.0}},
            {"path": "b.wav", "match_gain_db": -4.0, "alignment": {"alignable": true,
             "offset_s": 0.0, "confidence": 1.0}}]}"#,
        )
        .unwrap(),
    );
    assert!(state.matched_shown());
    assert!(state.rebuild_for(1), "B matched now");
    state.layout = CompareLayout::SideBySide;
    assert!(
        !state.matched_shown(),
        "side by side shows the levels as they are"
    );
    assert!(state.rebuild_for(1));
    state.layout = CompareLayout::Difference;
    state.pick_measure(Some(DifferenceMeasure::ALL[0]));
    assert!(!state.matched && state.measure == DifferenceMeasure::ALL[0]);
    assert!(!state.rebuild_for(1), "density, as side by side was built");
}

#[test]
fn scripted_layouts_are_named_as_the_tests_press_them() {
    assert_eq!(CompareLayout::named("off"), Some(CompareLayout::Off));
    assert_eq!(
        CompareLayout::named("side"),
        Some(CompareLayout::SideBySide)
    );
    assert_eq!(
        CompareLayout::named("difference"),
        Some(CompareLayout::Difference)
    );
    assert_eq!(CompareLayout::named("sides"), None);
}

/// What the window does to the compare goes through its methods: key B's switch (the version
/// heard is drawn beside A; A heard keeps the last one there), the tracks handed to the player
/// and back, the surfaces told once, a version's audio decoded only once it has loaded and
/// while it is not heard, and the scene built or failed.
#[test]
fn the_window_changes_the_compare_through_its_methods() {
    let mut state = CompareState::new(PathBuf::from("b.ply"));
    state.add(PathBuf::from("c.ply")).unwrap();
    state.heard(Listening(2));
    assert_eq!(
        (state.listening, state.beside),
        (Listening(2), Listening(2))
    );
    state.heard(Listening::A);
    assert_eq!(
        (state.listening, state.beside),
        (Listening::A, Listening(2))
    );

    let demo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/demo_song.flac");
    let track = || crate::playback::decode(&demo).unwrap();
    state.put_track(Listening::B, Some(track()));
    assert!(state.take_track(Listening::B).is_some());
    assert!(
        state.take_track(Listening::B).is_none(),
        "taken by the player"
    );
    state.put_track(Listening(3), Some(track()));
    assert!(
        state.take_track(Listening(3)).is_none(),
        "no version D: nothing kept"
    );

    let told = (SurfaceMethod::DualContouring, 0.5f32.to_bits(), 10, 12);
    assert!(state.tell_surfaces(told));
    assert!(!state.tell_surfaces(told), "told once");
    assert!(state.tell_surfaces((SurfaceMethod::MarchingTetrahedra, told.1, 10, 12)));

    let mut asked = 0;
    state.decode_audio_of(Listening::B, |_| {
        asked += 1;
        channel().1
    });
    assert_eq!(asked, 0, "B has not loaded");
    state.versions[0].loaded = Some(Arc::new(cloud(10)));
    state.heard(Listening::B);
    state.decode_audio_of(Listening::B, |_| {
        asked += 1;
        channel().1
    });
    assert_eq!(asked, 0, "B is heard: the player has its song");
    state.heard(Listening::A);
    state.decode_audio_of(Listening::B, |_| {
        asked += 1;
        channel().1
    });
    assert_eq!(asked, 1);
    assert!(state.versions[0].decoding.is_some());

    state.scene_failed("no union axes".into());
    assert!(state.clouds.is_none() && state.error.is_some());
    let a = cloud(10);
    let labels =
        crate::ui::labels::axis_labels_for_box(&a, glam::Vec3::splat(-1.0), glam::Vec3::ONE);
    state.scene_built(Arc::new((a, cloud(10))), labels);
    assert!(state.clouds.is_some() && state.labels.is_some() && state.error.is_none());
    state.set_layout(CompareLayout::Difference);
    assert_eq!(state.layout, CompareLayout::Difference);
}

/// Until the scene has grids the halves are drawn with the points' settings whatever the view:
/// the pictures they hold stay valid, so the frame of a click on Surface draws no point again
/// (both versions' every point, seconds on a slow device) before the window shows the click.
#[test]
fn the_halves_keep_their_points_picture_until_the_grids_come() {
    let mut state = CompareState::new(PathBuf::from("b.ply"));
    state.clouds = Some(Arc::new((cloud(10), cloud(12))));
    assert!(state.rebuild_for(1));
    let points = RenderSettings::default();
    assert_eq!(points.view, ViewKind::Points);
    for view in [ViewKind::Surface, ViewKind::Volume] {
        let asked = RenderSettings {
            view,
            ..points.clone()
        };
        assert_eq!(
            state.halves_settings(&asked),
            state.halves_settings(&points),
            "{view:?} before the grids: the picture of the points is kept"
        );
        assert_eq!(asked.view, view, "the view asked for is left as it is");
    }
    state.grids_installed();
    let surface = RenderSettings {
        view: ViewKind::Surface,
        ..points.clone()
    };
    assert_eq!(state.halves_settings(&surface).view, ViewKind::Surface);
    assert_eq!(state.halves_settings(&points).view, ViewKind::Points);
    // A new scene (another song in A) has no grids until they are built for it.
    assert!(state.rebuild_for(2));
    assert_eq!(state.halves_settings(&surface).view, ViewKind::Points);
    state.grids_installed();
    state.scene_failed("no union axes".into());
    assert_eq!(state.halves_settings(&surface).view, ViewKind::Points);
}

/// "building the compare grids…" is said once: by the status line when it says it, by the
/// view's badge otherwise (a reopened compare showed it in both places at once).
#[test]
fn the_grids_being_built_are_told_in_one_place() {
    let mut state = CompareState::new(PathBuf::from("b.ply"));
    assert_eq!(state.badge(false, None), None, "nothing to wait for");
    let (_sender, receiver) = channel();
    state.building(VoxelSettings::default(), receiver);
    assert_eq!(
        state.badge(false, Some(GRIDS_BUSY)),
        None,
        "the status line says it"
    );
    assert_eq!(
        state.badge(true, Some(GRIDS_BUSY)),
        None,
        "the grids come before any surface"
    );
    assert_eq!(
        state.badge(false, Some("drawing the volume…")),
        Some(GRIDS_BUSY),
        "the status line says something else"
    );
    assert_eq!(state.badge(false, None), Some(GRIDS_BUSY));
    assert!(state.rebuild_for(1));
    assert_eq!(state.badge(true, None), Some("extracting surface…"));
}

/// The difference's read-back for the read-outs runs on a thread: the state waits for its
/// answer, starts no second one meanwhile, says so in the Difference view, and drops it when
/// the scene or its grids change.
#[test]
fn the_difference_is_read_back_off_the_window_thread() {
    let copy = |measure| DifferenceCopy {
        shown: Field {
            dims: glam::UVec3::ONE,
            box_min: glam::Vec3::ZERO,
            box_max: glam::Vec3::ONE,
            density: vec![0.0],
            hp_mean: vec![0.0],
        },
        difference: vec![0.25],
        columns: vec![0.0],
        measure,
        range: 0.5,
    };
    let mut state = CompareState::new(PathBuf::from("b.ply"));
    state.layout = CompareLayout::Difference;
    assert!(state.difference_stale());
    let (sender, receiver) = channel();
    state.reading_difference(receiver);
    assert!(!state.difference_stale(), "one read-back at a time");
    assert!(state.poll_difference_read().is_none(), "nothing came yet");
    assert_eq!(state.badge(false, None), Some(DIFFERENCE_BUSY));
    state.layout = CompareLayout::SideBySide;
    assert_eq!(state.badge(false, None), None, "no read-outs shown there");
    sender.send(Some(copy(state.measure))).unwrap();
    assert_eq!(
        state.poll_difference_read().map(|c| c.range),
        Some(0.5),
        "the copy came"
    );
    assert!(state.difference.is_some() && state.difference_reading.is_none());
    assert!(!state.difference_stale());

    // A read-back for the old measure is read again once it came.
    let (sender, receiver) = channel();
    state.forget_difference();
    state.reading_difference(receiver);
    let old = state.measure;
    state.measure = DifferenceMeasure::ALL[1];
    assert!(!state.difference_stale());
    sender.send(Some(copy(old))).unwrap();
    assert!(state.poll_difference_read().is_some());
    assert!(state.difference_stale(), "read for another measure");

    // New grids drop a read-back of the old ones; a thread gone answers nothing.
    let (_sender, receiver) = channel();
    state.reading_difference(receiver);
    state.grids_installed();
    assert!(state.difference_reading.is_none() && state.difference.is_none());
    let (sender, receiver) = channel::<Option<DifferenceCopy>>();
    state.reading_difference(receiver);
    drop(sender);
    assert!(state.poll_difference_read().is_none());
    assert!(state.difference_reading.is_none(), "not waited for again");
}

/// The grids wait for the versions' alignment: it moves the version beside A when it comes
/// and the scene is built again, so grids built before it were built twice (a reopened compare
/// in the Surface view built both grids once for B as it was and again for B aligned). The
/// points stand in meanwhile.
#[test]
fn the_grids_are_built_once_the_alignment_came() {
    let mut state = CompareState::new(PathBuf::from("b.ply"));
    state.clouds = Some(Arc::new((cloud(10), cloud(12))));
    assert!(state.rebuild_for(1));
    let voxels = VoxelSettings::default();
    let (sender, receiver) = channel();
    state
        .alignment
        .start(vec!["a.wav".into(), "b.wav".into()], receiver);
    assert_eq!(state.grid_step(&voxels, false), GridStep::Align);
    assert_eq!(state.grid_step(&voxels, false), GridStep::Align);
    assert!(!state.grids_building());
    assert_eq!(
        state.grid_step(&voxels, true),
        GridStep::Ready,
        "grids built already are drawn"
    );
    sender.send(Err("no audio".into())).unwrap();
    assert_eq!(state.alignment.poll(), Some(false));
    assert_eq!(state.grid_step(&voxels, false), GridStep::Start);

    // A version still loading starts a comparison of its own when it has loaded.
    let _loading = adding(&mut state, "c.ply");
    assert!(state.loading());
    assert_eq!(state.grid_step(&voxels, false), GridStep::Align);
}
