//! The integration tests, one crate: each former `tests/NAME.rs` is the module `NAME`, so
//! `cargo test --test it NAME::` runs one file's tests (`cargo test --test it surface::` for
//! tests/it/surface*). One binary links wgpu, eframe and the app's library once instead of once
//! per file (docs/ARCHITECTURE.md, "Tests"). The tests share one process: files they write go
//! to folders of their own (`common::fresh_dir`, `loader_files::scratch_dir`), and nothing here
//! sets environment variables or the working folder of the test process (children get theirs).

mod common;
mod loader_files;

mod big_clouds;
mod cli;
mod cli_bench;
mod cli_safety;
mod cloud_loader;
mod cloud_loader_malformed;
mod colours;
mod compare;
mod compare_align;
mod compare_refine;
mod format_fixtures;
mod freq_axis;
mod gpu_limits;
mod layout;
mod normalize_left_out;
mod open_audio;
mod page;
mod pick;
mod playback;
mod reliability_cache;
// Its stand-in extractors are shell scripts, its locks and PIDs are Unix's.
#[cfg(unix)]
mod reliability_cache_shared;
mod reliability_loader;
mod render_points;
mod screenshot;
mod source_checked;
mod surface;
mod text_scripts;
mod video;
mod video_trust;
mod volume;
mod volume_skip;
mod voxelize;
mod window;
mod window_compare;
mod window_compare_align;
mod window_compare_refine;
mod window_compare_save;
mod window_compare_surface;
mod window_heard;
mod window_messages;
mod window_open_audio;
mod window_open_music;
mod window_persist;
mod window_responsive;
mod window_save_big;
mod window_save_safety;
mod window_save_wait;
mod window_stream;
mod window_strip;
mod window_timeline_build;
mod window_video_export;
