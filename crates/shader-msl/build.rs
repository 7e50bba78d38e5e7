//! The app's shader sources are compiled into this crate's tests without the app's wgpu glue.
fn main() {
    println!("cargo::rustc-cfg=shader_text_only");
}
