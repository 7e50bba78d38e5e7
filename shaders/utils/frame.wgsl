// Per-frame values shared by every pass: bind group 0, binding 0.
// Keep in sync with FrameUniforms in src/render/gpu/frame.rs.
struct Frame {
    // Clip space from data space (the cloud's normalized [-1, 1] coordinates).
    clip_from_data: mat4x4<f32>,
    data_from_clip: mat4x4<f32>,
    // Eye position in data space (w = 1).
    eye_position: vec4<f32>,
    // width, height, 1 / width, 1 / height in pixels.
    viewport: vec4<f32>,
    // Direction toward the light in data space (w unused).
    light_direction: vec4<f32>,
    // x: frame counter (jitter seeds), y: 1 while the camera moves, z, w: unused.
    flags: vec4<u32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;
