//! Every WGSL module the app builds must parse, validate and translate to MSL (Metal), since
//! macOS users run the Metal backend, which takes shaders through naga's MSL writer.

use naga::back::msl;
use naga::valid::{Capabilities, ValidationFlags, Validator};

#[test]
fn every_shader_translates_to_msl() {
    let shaders = loudscape::render::shaders::all();
    assert!(
        shaders.len() >= 3,
        "expected the app's shader modules, found {}",
        shaders.len()
    );
    for (name, source) in shaders {
        let module = naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| {
            panic!(
                "{name}: WGSL does not parse:\n{}",
                e.emit_to_string(&source)
            )
        });
        let info = Validator::new(ValidationFlags::all(), Capabilities::all())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{name}: WGSL does not validate: {e:?}"));
        let options = msl::Options {
            lang_version: (2, 4),
            ..Default::default()
        };
        let pipeline_options = msl::PipelineOptions::default();
        let (text, _) = msl::write_string(&module, &info, &options, &pipeline_options)
            .unwrap_or_else(|e| panic!("{name}: MSL translation failed: {e}"));
        assert!(
            text.contains("metal_stdlib"),
            "{name}: MSL output does not look like Metal source"
        );
        // Every entry point must come out as a Metal function.
        for entry in &module.entry_points {
            assert!(
                text.contains(&entry.name),
                "{name}: entry point {} missing from the MSL",
                entry.name
            );
        }
    }
}
