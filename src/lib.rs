//! loudscape: see how music is loud.
//!
//! The library half of the app, one floor of the data flow a module; each imports only from the
//! floors below it (the full map, file by file, is in docs/ARCHITECTURE.md):
//!
//! - [`data`]: point clouds from PLY files (`data::cloud`: header, metadata, the fast path for
//!   loudscape files, generic PLY, the writer), axes in physical units, fields on a box, and
//!   data made in code for tests and benchmarks.
//! - [`view`]: the orbit camera and what lies under a pixel (no GPU).
//! - [`playback`]: the source audio, its output and clock (no GPU, no window).
//! - [`render`]: the GPU passes, which know nothing of the window: `gpu/` plumbing, `grid/`
//!   (voxelize), `surface/` (marching tetrahedra, dual contouring, draw), points, lines,
//!   markers, volume, composite; `scene` owns them (once per device) and each cloud's data.
//! - [`annotate`]: picture annotation as plain data (axis labels, legends, titles, the loudness
//!   strip: text boxes, rectangles, lines, measured in the window's font) and its drawing on
//!   the CPU; no egui, no GPU.
//! - [`picture`]: pictures without a window: a view rendered offscreen, read back, annotated,
//!   saved as PNG; A/B compare pictures. What `render` and `video` draw.
//! - [`files`]: writing files safely: temporary files removed on errors and signals, outputs
//!   that are not inputs.
//! - [`ui`]: everything egui: the window, its panels, hover, persistence; it paints the
//!   annotation laid out by [`annotate`].
//!
//! The binary (`src/main.rs`) adds the command line (`src/commands/`).

/// Makes a closed vocabulary (a type with an `ALL` list) a [`clap::ValueEnum`] named by
/// `$name` (the command-line spelling, lower case): the command line parses it once where it
/// enters and lists the choices in its messages, and the window hands it back to a command
/// under the same name ([`value_name`]). One list of names for the command line, the window
/// and the docs.
macro_rules! command_line_names {
    ($type:ty, |$value:ident| $name:expr) => {
        impl clap::ValueEnum for $type {
            fn value_variants<'a>() -> &'a [Self] {
                &Self::ALL
            }

            fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
                let $value = *self;
                Some(clap::builder::PossibleValue::new($name))
            }
        }
    };
}

pub mod annotate;
pub mod data;
#[cfg(not(target_arch = "wasm32"))]
pub mod extract;
#[cfg(not(target_arch = "wasm32"))]
pub mod files;
#[cfg(not(target_arch = "wasm32"))]
pub mod picture;
#[cfg(not(target_arch = "wasm32"))]
pub mod playback;
pub mod render;
#[cfg(not(target_arch = "wasm32"))]
pub mod ui;
pub mod view;
#[cfg(target_arch = "wasm32")]
pub mod web;

/// The command-line name of a value of a closed vocabulary (`points`, `mt`, `spotify`), as the
/// command line parses it: what the window writes when it hands its settings to a command.
pub fn value_name<T: clap::ValueEnum>(value: &T) -> String {
    value
        .to_possible_value()
        .map(|v| v.get_name().to_string())
        .unwrap_or_default()
}

/// Parses a closed vocabulary's command-line name, any case (for names read back from a
/// settings file); None for a name that is not one of them.
pub fn parse_value<T: clap::ValueEnum>(name: &str) -> Option<T> {
    T::from_str(name.trim(), true).ok()
}
