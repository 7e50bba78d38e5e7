//! Every WGSL module the app builds must parse, validate and translate to MSL (Metal), since
//! macOS users run the Metal backend, which takes shaders through naga's MSL writer; they validate
//! with no optional capability, as the device asks for no feature a shader would need.

use naga::back::msl;
use naga::valid::{Capabilities, ValidationFlags, Validator};

#[test]
fn every_shader_translates_to_msl() {
    let shaders = loudscape_shader_msl::shaders::all();
    let mut translated_entry_points = Vec::new();
    for (name, source) in shaders {
        let module = naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| {
            panic!(
                "{name}: WGSL does not parse:\n{}",
                e.emit_to_string(&source)
            )
        });
        // No optional capability: the device asks for no feature a shader would need.
        let info = Validator::new(ValidationFlags::all(), Capabilities::empty())
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
            translated_entry_points.push(entry.name.clone());
        }
    }
    // Every entry point written in shaders/ reached the MSL writer through some module: a
    // shader file left out of `shaders::all()` would otherwise never be translated.
    let written = entry_points_in_shader_files(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shaders"
    )));
    assert!(
        written.len() >= 11,
        "expected the entry points of shaders/, found {written:?}"
    );
    for (file, entry) in written {
        assert!(
            translated_entry_points.contains(&entry),
            "{file}: entry point {entry} is in no module of shaders::all(), so it is never translated to MSL"
        );
    }
}

/// (file, function name) of every `@compute`, `@vertex` or `@fragment` function under `dir`.
fn entry_points_in_shader_files(dir: &std::path::Path) -> Vec<(String, String)> {
    let mut found = Vec::new();
    let mut folders = vec![dir.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).expect("shaders/ is readable") {
            let path = entry.expect("a shaders/ entry").path();
            if path.is_dir() {
                folders.push(path);
                continue;
            }
            if path.extension().and_then(|e| e.to_str()) != Some("wgsl") {
                continue;
            }
            let text = std::fs::read_to_string(&path).expect("a shader file is UTF-8");
            let mut stage_seen = false;
            for line in text.lines() {
                let line = line.trim();
                if line.starts_with("//") {
                    continue;
                }
                if ["@compute", "@vertex", "@fragment"]
                    .iter()
                    .any(|stage| line.starts_with(stage))
                {
                    stage_seen = true;
                }
                if stage_seen && let Some(rest) = line.split("fn ").nth(1) {
                    let name: String = rest
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    found.push((path.display().to_string(), name));
                    stage_seen = false;
                }
            }
        }
    }
    found
}
