//! Axes in physical units. (Stand-in until the loader lands.)
#[derive(Clone, Debug, Default)]
pub struct Tick {
    pub at: f32,
    pub label: String,
}
#[derive(Clone, Debug, Default)]
pub struct Axis {
    pub label: String,
    pub unit: String,
    pub min: f64,
    pub max: f64,
}
impl Axis {
    pub fn ticks(&self, _max_count: usize) -> Vec<Tick> {
        (0..=4)
            .map(|i| {
                let at = -1.0 + 0.5 * i as f32;
                let v = self.min + (self.max - self.min) * f64::from(at + 1.0) * 0.5;
                Tick {
                    at,
                    label: format!("{v:.0} {}", self.unit),
                }
            })
            .collect()
    }
}
