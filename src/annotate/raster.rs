//! Shapes drawn onto an image on the CPU (vello_cpu, anti-aliased, blended in the image's
//! sRGB-encoded values as the window's egui blends in its gamma-encoded target). Text is shaped
//! by [`super::font`]: in visual order, each run in its direction and its fallback font.

use vello_cpu::color::{AlphaColor, Srgb};
use vello_cpu::kurbo::{self, Affine, BezPath, Shape as _};
use vello_cpu::{CompositeMode, PixmapMut, RasterizerSettings, RenderContext, Resources};

use super::font::{Outliner, shape};
use super::{Rect, Rgba, Shape, Text};

/// Draws `shapes` (in points) over `image`, `pixels_per_point` pixels a point, clipped to it.
/// Images wider or taller than 65535 pixels are left as they are.
pub fn draw(image: &mut image::RgbaImage, shapes: &[Shape], pixels_per_point: f32) {
    let (width, height) = image.dimensions();
    if let Some(mut prepared) = Prepared::new(shapes, pixels_per_point, width, height) {
        prepared.paint(image.as_mut());
    }
}

/// Shapes laid out and rasterized once for pictures of one size, painted over as many as
/// wanted: a video whose labels stay put draws the same overlay on every frame, and paints it
/// exactly as [`draw`] does without shaping its text again.
pub struct Prepared {
    ctx: RenderContext,
    resources: Resources,
    width: u16,
    height: u16,
}

impl Prepared {
    /// `None` where there is nothing to draw or the picture is wider or taller than 65535.
    pub fn new(shapes: &[Shape], pixels_per_point: f32, width: u32, height: u32) -> Option<Self> {
        let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
            return None;
        };
        if shapes.is_empty() || w == 0 || h == 0 {
            return None;
        }
        let ppp = f64::from(pixels_per_point.max(0.01));
        let mut ctx = RenderContext::new(w, h);
        for shape in shapes {
            add_shape(&mut ctx, shape, ppp);
        }
        ctx.flush();
        Some(Self {
            ctx,
            resources: Resources::new(),
            width: w,
            height: h,
        })
    }

    /// Paints the shapes over `rgba`, an opaque picture of the prepared size as straight RGBA8
    /// rows; a buffer of another length is left as it is.
    pub fn paint(&mut self, rgba: &mut [u8]) {
        // The image is opaque (a rendered picture), so its straight RGBA is also premultiplied.
        let Some(target) = PixmapMut::new(self.width, self.height, rgba) else {
            return;
        };
        let settings = RasterizerSettings {
            composite_mode: CompositeMode::SrcOver,
            ..RasterizerSettings::default()
        };
        self.ctx.render_with(target, &mut self.resources, settings);
        // Source-over onto an opaque pixel is opaque, but the rasterizer's 8-bit arithmetic can
        // round an edge pixel's alpha to 254 (a notebook's picture had translucent text edges).
        for pixel in rgba.chunks_exact_mut(4) {
            pixel[3] = 255;
        }
    }
}

fn add_shape(ctx: &mut RenderContext, shape: &Shape, ppp: f64) {
    match shape {
        Shape::Fill {
            rect,
            radius,
            colour,
        } => {
            ctx.set_transform(Affine::scale(ppp));
            ctx.set_paint(paint(*colour));
            if *radius > 0.0 {
                let rounded = kurbo::RoundedRect::from_rect(k_rect(rect), f64::from(*radius));
                ctx.fill_path(&rounded.to_path(0.05));
            } else {
                ctx.fill_rect(&k_rect(rect));
            }
        }
        Shape::Frame {
            rect,
            width,
            colour,
        } => {
            ctx.set_transform(Affine::scale(ppp));
            ctx.set_paint(paint(*colour));
            ctx.set_stroke(kurbo::Stroke::new(f64::from(*width)));
            let half = width * 0.5;
            ctx.stroke_rect(&k_rect(&rect.expand(half)));
        }
        Shape::Line {
            points,
            width,
            colour,
        } => {
            let Some((first, rest)) = points.split_first() else {
                return;
            };
            ctx.set_transform(Affine::scale(ppp));
            ctx.set_paint(paint(*colour));
            ctx.set_stroke(kurbo::Stroke::new(f64::from(*width)));
            let mut path = BezPath::new();
            path.move_to(point(*first));
            for p in rest {
                path.line_to(point(*p));
            }
            ctx.stroke_path(&path);
        }
        Shape::Text(text) => draw_text(ctx, text, ppp),
    }
}

fn draw_text(ctx: &mut RenderContext, text: &Text, ppp: f64) {
    let px = text.size * ppp as f32;
    let shaped = shape(&text.text, px);
    let mut outliner = Outliner::new(px);
    // egui puts the box's top left and each glyph's baseline on whole pixels, and its glyphs on
    // quarter pixels across.
    let left = (f64::from(text.rect.left()) * ppp).round();
    let top = (f64::from(text.rect.top()) * ppp).round();
    ctx.set_transform(Affine::IDENTITY);
    ctx.set_paint(paint(text.colour));
    for glyph in &shaped.glyphs {
        let x = left + (f64::from(glyph.x) * 4.0).round() / 4.0;
        let baseline = top + f64::from(glyph.y).round();
        if let Some(path) = outliner.outline(glyph.face, glyph.glyph, x, baseline) {
            ctx.fill_path(&path);
        }
    }
}

fn paint(c: Rgba) -> AlphaColor<Srgb> {
    AlphaColor::from_rgba8(c[0], c[1], c[2], c[3])
}

fn point(p: [f32; 2]) -> kurbo::Point {
    kurbo::Point::new(f64::from(p[0]), f64::from(p[1]))
}

fn k_rect(r: &Rect) -> kurbo::Rect {
    kurbo::Rect::new(
        f64::from(r.min[0]),
        f64::from(r.min[1]),
        f64::from(r.max[0]),
        f64::from(r.max[1]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::annotate::{Anchor, Annotation};

    #[test]
    fn shapes_land_where_they_are_laid_out_and_blend_over_the_picture() {
        let mut image = image::RgbaImage::from_pixel(80, 40, image::Rgba([0, 0, 80, 255]));
        let mut a = Annotation::default();
        a.fill(
            Rect::from_min_size([10.0, 10.0], [10.0, 10.0]),
            0.0,
            [255, 0, 0, 255],
        );
        a.fill(
            Rect::from_min_size([30.0, 10.0], [10.0, 10.0]),
            0.0,
            [255, 255, 255, 128],
        );
        let label = a.text(Text::new(
            "Hg",
            [50.0, 5.0],
            Anchor::LEFT_TOP,
            14.0,
            [255; 4],
        ));
        draw(&mut image, &a.shapes, 1.0);
        assert_eq!(image.get_pixel(15, 15).0, [255, 0, 0, 255]);
        let half = image.get_pixel(35, 15).0;
        assert!((120..=136).contains(&half[0]) && half[2] > 150, "{half:?}");
        assert_eq!(image.get_pixel(5, 5).0, [0, 0, 80, 255]);
        // Ink inside the text's box, none right of it.
        let inked =
            |x0: u32, x1: u32| (x0..x1).any(|x| (0..40).any(|y| image.get_pixel(x, y)[0] > 128));
        assert!(inked(label.left() as u32, label.right().ceil() as u32));
        assert!(!inked(label.right().ceil() as u32 + 2, 80));
        // Twice the pixels a point: the box is drawn twice as large.
        let mut big = image::RgbaImage::from_pixel(160, 80, image::Rgba([0, 0, 80, 255]));
        draw(&mut big, &a.shapes, 2.0);
        assert_eq!(big.get_pixel(30, 30).0, [255, 0, 0, 255]);
        assert_eq!(big.get_pixel(19, 30).0, [0, 0, 80, 255]);
        // The picture stays opaque, text edges and translucent fills included (a label's plate
        // over the dark background left alpha 254 where the rasterizer rounded).
        let mut plated = image::RgbaImage::from_pixel(40, 20, image::Rgba([14, 16, 20, 255]));
        let mut plate = Annotation::default();
        plate.fill(
            Rect::from_min_size([2.3, 2.7], [30.0, 12.0]),
            3.0,
            crate::annotate::axes::LABEL_PLATE,
        );
        draw(&mut plated, &plate.shapes, 1.0);
        let mut all = image.pixels().chain(big.pixels()).chain(plated.pixels());
        assert!(all.all(|p| p[3] == 255));
    }

    /// `text` drawn white at 20 points on black, alone.
    fn drawn(text: &str) -> image::RgbaImage {
        let mut image = image::RgbaImage::from_pixel(48, 40, image::Rgba([0, 0, 0, 255]));
        let mut a = Annotation::default();
        a.text(Text::new(
            text,
            [4.0, 4.0],
            Anchor::LEFT_TOP,
            20.0,
            [255; 4],
        ));
        draw(&mut image, &a.shapes, 1.0);
        image
    }

    #[test]
    fn hebrew_arabic_and_emoji_are_drawn_as_letters_not_the_empty_box() {
        // A character no font has is drawn as Ubuntu Light's empty box: what every one of these
        // was drawn as before the fallback fonts.
        let empty_box = drawn("\u{10FFFD}");
        let ink = |image: &image::RgbaImage| image.pixels().filter(|p| p[0] > 100).count();
        assert!(ink(&empty_box) > 20);
        for c in "שלוםمرحباब🎵😀🔊".chars() {
            let letter = drawn(&c.to_string());
            let differing = letter
                .pixels()
                .zip(empty_box.pixels())
                .filter(|(a, b)| a[0].abs_diff(b[0]) > 60)
                .count();
            assert!(ink(&letter) > 10, "{c} has no ink");
            assert!(
                differing * 4 > ink(&empty_box),
                "{c} is drawn as the empty box ({differing} pixels differ)"
            );
        }
    }
}
