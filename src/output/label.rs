//! Text on 8-bit previews: a frame number in a corner of a contact
//! sheet's thumbnail, white on a dark box so it reads over any picture.
//! The font (DejaVu Sans cut down to ASCII, `assets/fonts/`) is embedded
//! in the binary: no system font library is needed.

use ab_glyph::{point, Font, FontRef, PxScale, ScaleFont};

/// The embedded font's file.
pub const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-ascii.ttf");

/// An RGBA8 image, row-major, top row first.
pub struct Canvas<'a> {
    pub width: u32,
    pub height: u32,
    pub bytes: &'a mut [u8],
}

impl Canvas<'_> {
    /// Blends `colour` over the pixel at (`x`, `y`) by `coverage`; pixels
    /// outside the canvas are left alone.
    fn blend(&mut self, x: i64, y: i64, colour: [u8; 3], coverage: f32) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let at = 4 * (y as usize * self.width as usize + x as usize);
        let coverage = coverage.clamp(0.0, 1.0);
        for (channel, &value) in colour.iter().enumerate() {
            let old = self.bytes[at + channel] as f32;
            let new = old + (value as f32 - old) * coverage;
            self.bytes[at + channel] = new.round() as u8;
        }
        self.bytes[at + 3] = 255;
    }
}

/// The embedded font, parsed; None only if the file embedded is broken.
pub fn label_font() -> Option<FontRef<'static>> {
    FontRef::try_from_slice(FONT).ok()
}

/// Draws `text` in `font`, `size` pixels high, with its box's top-left
/// corner at (`left`, `top`), clipped to the canvas.
pub fn draw_label(
    canvas: &mut Canvas,
    font: &FontRef,
    (left, top): (u32, u32),
    text: &str,
    size: f32,
) {
    let scale = PxScale::from(size);
    let scaled = font.as_scaled(scale);
    let padding = (size / 6.0).ceil();
    let width: f32 = text
        .chars()
        .map(|c| scaled.h_advance(font.glyph_id(c)))
        .sum();
    let (box_width, box_height) = (width + 2.0 * padding, scaled.height() + 2.0 * padding);
    for y in 0..box_height.ceil() as i64 {
        for x in 0..box_width.ceil() as i64 {
            canvas.blend(left as i64 + x, top as i64 + y, [0, 0, 0], 0.6);
        }
    }
    let mut caret = left as f32 + padding;
    let baseline = top as f32 + padding + scaled.ascent();
    for c in text.chars() {
        let id = font.glyph_id(c);
        let glyph = id.with_scale_and_position(scale, point(caret, baseline));
        caret += scaled.h_advance(id);
        let Some(outline) = font.outline_glyph(glyph) else {
            continue;
        };
        let bounds = outline.px_bounds();
        outline.draw(|x, y, coverage| {
            let (x, y) = (
                bounds.min.x as i64 + x as i64,
                bounds.min.y as i64 + y as i64,
            );
            canvas.blend(x, y, [255, 255, 255], coverage);
        });
    }
}
