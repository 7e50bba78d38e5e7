// Frequency axis at view time (src/data/freq_axis.rs): a song point's stored z (its STFT bin's
// frequency, linear or log as extracted) -> the bin index -> the view's z, spread over the bin's
// range in the view by a deterministic jitter of the point index.
// A pass that prepends this file declares `params` with a field `freq: FreqParams` and
// `freq_table: array<vec2<f32>>` (per bin: the view's z range lo, hi; lo > hi: left out).
// Keep FreqParams, freq_jitter and freq_view_z in sync with src/data/freq_axis.rs.

struct FreqParams {
    // x: 0 as stored, 1 bin index linear in z, 2 exponential in z; y: bins in the table;
    // z: index of the chunk's first point in the cloud; w: unused.
    mode: vec4<u32>,
    // x, y: bin index = floor(x z + y + 0.5) (mode 1) or floor(exp2(x z + y) + 0.5) (mode 2).
    bin_of_z: vec4<f32>,
};

// The view's z of a point the view leaves out (outside every box).
const FREQ_HIDDEN: f32 = 4.0;

// A number in [0, 1) per point index: the PCG hash, 24 bits (exact in f32).
fn freq_jitter(index: u32) -> f32 {
    let state = index * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    let hash = (word >> 22u) ^ word;
    return f32(hash >> 8u) * (1.0 / 16777216.0);
}

// The view's z of point `index` of the chunk (stored z `z`), or FREQ_HIDDEN.
fn freq_view_z(z: f32, index: u32) -> f32 {
    let f = params.freq;
    if (f.mode.x == 0u) {
        return z;
    }
    let t = f.bin_of_z.x * z + f.bin_of_z.y;
    var k = t;
    if (f.mode.x == 2u) {
        k = exp2(t);
    }
    let bin = u32(clamp(floor(k + 0.5), 0.0, f32(f.mode.y - 1u)));
    let range = freq_table[bin];
    if (range.x > range.y) {
        return FREQ_HIDDEN;
    }
    return range.x + freq_jitter(f.mode.z + index) * (range.y - range.x);
}
