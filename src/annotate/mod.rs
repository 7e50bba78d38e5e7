//! Picture annotation as plain data: axis tick labels and titles, colour keys, names and titles,
//! the loudness strip, laid out as [`Shape`]s (text with its measured box, filled and framed
//! rectangles, lines) in points. Nothing here knows egui: the window paints the shapes with its
//! painter (`ui::annotation`), and headless pictures (`render`, `video`, compare pictures, the
//! window's Save PNG) draw them onto the read-back image on the CPU ([`raster::draw`]) in the
//! window's font ([`font`]), so both look alike.
//!
//! Layout rules live here and are tested on the data: text never overlaps text already placed
//! (ticks make way for titles), a title moves in from the picture's edge, a legend's key moves
//! under its name where the two would meet.

pub mod axes;
pub mod bidi;
pub mod compare;
pub mod font;
pub mod legend;
pub mod overlay;
pub mod raster;
pub mod strip;

#[cfg(test)]
mod layout_tests;

/// A colour, straight (not premultiplied) RGBA, sRGB-encoded as the render target holds it.
pub type Rgba = [u8; 4];

/// Opaque `[r, g, b]`.
pub const fn rgb(c: [u8; 3]) -> Rgba {
    [c[0], c[1], c[2], 255]
}

/// An axis-aligned rectangle in points, `min` top left.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rect {
    pub min: [f32; 2],
    pub max: [f32; 2],
}

impl Rect {
    pub fn from_min_max(min: [f32; 2], max: [f32; 2]) -> Self {
        Self { min, max }
    }

    pub fn from_min_size(min: [f32; 2], size: [f32; 2]) -> Self {
        Self {
            min,
            max: [min[0] + size[0], min[1] + size[1]],
        }
    }

    pub fn left(&self) -> f32 {
        self.min[0]
    }
    pub fn right(&self) -> f32 {
        self.max[0]
    }
    pub fn top(&self) -> f32 {
        self.min[1]
    }
    pub fn bottom(&self) -> f32 {
        self.max[1]
    }
    pub fn width(&self) -> f32 {
        self.max[0] - self.min[0]
    }
    pub fn height(&self) -> f32 {
        self.max[1] - self.min[1]
    }
    pub fn center(&self) -> [f32; 2] {
        [
            (self.min[0] + self.max[0]) * 0.5,
            (self.min[1] + self.max[1]) * 0.5,
        ]
    }

    /// Grown by `x` left and right, `y` above and below.
    pub fn expand2(&self, x: f32, y: f32) -> Self {
        Self {
            min: [self.min[0] - x, self.min[1] - y],
            max: [self.max[0] + x, self.max[1] + y],
        }
    }

    pub fn expand(&self, by: f32) -> Self {
        self.expand2(by, by)
    }

    pub fn translate(&self, dx: f32, dy: f32) -> Self {
        Self {
            min: [self.min[0] + dx, self.min[1] + dy],
            max: [self.max[0] + dx, self.max[1] + dy],
        }
    }

    /// Whether the two overlap (touching edges do not).
    pub fn intersects(&self, other: &Rect) -> bool {
        self.min[0] < other.max[0]
            && other.min[0] < self.max[0]
            && self.min[1] < other.max[1]
            && other.min[1] < self.max[1]
    }

    pub fn contains(&self, p: [f32; 2]) -> bool {
        (self.min[0]..=self.max[0]).contains(&p[0]) && (self.min[1]..=self.max[1]).contains(&p[1])
    }
}

/// Where a text's box sits against its position, per axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    Min,
    Center,
    Max,
}

/// Which point of a text's box is at its position: `(horizontal, vertical)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Anchor(pub Align, pub Align);

impl Anchor {
    pub const LEFT_TOP: Self = Self(Align::Min, Align::Min);
    pub const CENTER_TOP: Self = Self(Align::Center, Align::Min);
    pub const RIGHT_TOP: Self = Self(Align::Max, Align::Min);
    pub const LEFT_CENTER: Self = Self(Align::Min, Align::Center);
    pub const RIGHT_CENTER: Self = Self(Align::Max, Align::Center);
    pub const LEFT_BOTTOM: Self = Self(Align::Min, Align::Max);
    pub const CENTER_BOTTOM: Self = Self(Align::Center, Align::Max);
    pub const RIGHT_BOTTOM: Self = Self(Align::Max, Align::Max);

    /// The box of `size` with this anchor at `pos`.
    pub fn rect(self, pos: [f32; 2], size: [f32; 2]) -> Rect {
        let offset = |align: Align, extent: f32| match align {
            Align::Min => 0.0,
            Align::Center => extent * 0.5,
            Align::Max => extent,
        };
        let min = [
            pos[0] - offset(self.0, size[0]),
            pos[1] - offset(self.1, size[1]),
        ];
        Rect::from_min_size(min, size)
    }
}

/// A line of text: its box (measured in the window's font at `size` points, top left on whole
/// points, as egui places text) and its colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Text {
    pub text: String,
    pub rect: Rect,
    /// Font size, points.
    pub size: f32,
    pub colour: Rgba,
}

impl Text {
    /// `text` at `size` points with `anchor` at `pos`.
    pub fn new(
        text: impl Into<String>,
        pos: [f32; 2],
        anchor: Anchor,
        size: f32,
        colour: Rgba,
    ) -> Self {
        let text = text.into();
        let measured = font::measure(&text, size);
        let rect = anchor.rect(pos, measured);
        let min = [rect.min[0].round(), rect.min[1].round()];
        Self {
            text,
            rect: Rect::from_min_size(min, measured),
            size,
            colour,
        }
    }

    /// Moved by `(dx, dy)`, kept on whole points.
    pub fn moved(mut self, dx: f32, dy: f32) -> Self {
        self.rect = self.rect.translate(dx.round(), dy.round());
        self
    }
}

/// One thing drawn over a picture, in points.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A filled rectangle, corners rounded by `radius`.
    Fill {
        rect: Rect,
        radius: f32,
        colour: Rgba,
    },
    /// A rectangle's outline, `width` wide, just outside `rect`.
    Frame {
        rect: Rect,
        width: f32,
        colour: Rgba,
    },
    /// A line through `points` (two for a segment).
    Line {
        points: Vec<[f32; 2]>,
        width: f32,
        colour: Rgba,
    },
    Text(Text),
}

/// Shapes in the order they are drawn.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Annotation {
    pub shapes: Vec<Shape>,
}

impl Annotation {
    pub fn push(&mut self, shape: Shape) {
        self.shapes.push(shape);
    }

    pub fn extend(&mut self, other: Annotation) {
        self.shapes.extend(other.shapes);
    }

    pub fn fill(&mut self, rect: Rect, radius: f32, colour: Rgba) {
        self.push(Shape::Fill {
            rect,
            radius,
            colour,
        });
    }

    pub fn line(&mut self, from: [f32; 2], to: [f32; 2], width: f32, colour: Rgba) {
        self.push(Shape::Line {
            points: vec![from, to],
            width,
            colour,
        });
    }

    /// Adds `text` and returns its box.
    pub fn text(&mut self, text: Text) -> Rect {
        let rect = text.rect;
        self.push(Shape::Text(text));
        rect
    }

    /// The boxes of what is drawn (texts, filled rectangles, frames), for laying out more
    /// clear of them.
    pub fn boxes(&self) -> Vec<Rect> {
        self.shapes
            .iter()
            .filter_map(|s| match s {
                Shape::Text(t) => Some(t.rect),
                Shape::Fill { rect, .. } | Shape::Frame { rect, .. } => Some(*rect),
                Shape::Line { .. } => None,
            })
            .collect()
    }

    /// The texts, in order.
    pub fn texts(&self) -> impl Iterator<Item = &Text> {
        self.shapes.iter().filter_map(|s| match s {
            Shape::Text(t) => Some(t),
            _ => None,
        })
    }
}
