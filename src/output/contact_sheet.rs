//! Contact sheets: a shot's frames as labelled thumbnails on one PNG, for
//! storyboard previews. Frames are shrunk as they are rendered (or read
//! back from disk, `shot_sheet.rs`), so a long shot holds thumbnails, not
//! frames; the sheet is about as wide as one frame, tone-mapped like the
//! previews, each thumbnail labelled with its frame number, in frame
//! order, and written once, atomically, at the end of the run.

use std::path::Path;

use glam::Vec4;

use super::label::{draw_label, label_font, Canvas};
use super::png::{preview_bytes, write_rgba8};
use super::{Image, OutputError};

/// A sheet being filled: every `every`-th frame of a run, `columns` to a
/// row.
pub struct ContactSheet {
    columns: u32,
    every: u32,
    /// Thumbnail size, from the first frame.
    cell: Option<(u32, u32)>,
    thumbnails: Vec<(u32, Image)>,
}

impl ContactSheet {
    /// `columns` and `every` of 0 count as 1.
    pub fn new(columns: u32, every: u32) -> ContactSheet {
        ContactSheet {
            columns: columns.max(1),
            every: every.max(1),
            cell: None,
            thumbnails: Vec::new(),
        }
    }

    /// Whether the sheet shows the `index`-th frame of its shot.
    pub fn shows(&self, index: usize) -> bool {
        index.is_multiple_of(self.every as usize)
    }

    /// Takes the `index`-th frame of the shot, frame number `frame`, if it
    /// is one the sheet shows, in its place by frame number. Each
    /// thumbnail is the first frame's size divided by the columns (at
    /// least one pixel), box-filtered: every thumbnail pixel is the mean
    /// of the frame's pixels under it.
    pub fn add(&mut self, index: usize, frame: u32, image: &Image) {
        if !self.shows(index) {
            return;
        }
        let columns = self.columns;
        let (width, height) = *self.cell.get_or_insert_with(|| {
            (
                (image.width / columns).max(1),
                (image.height / columns).max(1),
            )
        });
        let place = self.thumbnails.partition_point(|(shown, _)| *shown < frame);
        (self.thumbnails).insert(place, (frame, thumbnail(image, width, height)));
    }

    /// The sheet: thumbnails left to right, top to bottom; cells after the
    /// last stay transparent black. No frames give a 0×0 sheet.
    pub fn image(&self) -> Image {
        let Some((width, height)) = self.cell else {
            return Image::filled(0, 0, Vec4::ZERO);
        };
        let count = self.thumbnails.len() as u32;
        let used_columns = self.columns.min(count);
        let rows = count.div_ceil(self.columns);
        let mut sheet = Image::filled(used_columns * width, rows * height, Vec4::ZERO);
        for (index, (_, thumbnail)) in self.thumbnails.iter().enumerate() {
            let (left, top) = self.corner(index);
            for y in 0..height {
                let row = (top + y) as usize * sheet.width as usize + left as usize;
                let source = (y * width) as usize..((y + 1) * width) as usize;
                sheet.pixels[row..row + width as usize].copy_from_slice(&thumbnail.pixels[source]);
            }
        }
        sheet
    }

    /// Writes the sheet at `exposure` stops to `path`, atomically, each
    /// thumbnail labelled with its frame number.
    pub fn write(&self, path: &Path, exposure: f32) -> Result<(), OutputError> {
        let sheet = self.image();
        let mut bytes = preview_bytes(&sheet, exposure);
        let mut canvas = Canvas {
            width: sheet.width,
            height: sheet.height,
            bytes: &mut bytes,
        };
        let size = self
            .cell
            .map_or(0.0, |(_, height)| (height as f32 / 6.0).max(9.0));
        if let Some(font) = label_font() {
            for (index, (frame, _)) in self.thumbnails.iter().enumerate() {
                let (left, top) = self.corner(index);
                let corner = (left + 2, top + 2);
                draw_label(&mut canvas, &font, corner, &frame.to_string(), size);
            }
        }
        write_rgba8(path, sheet.width, sheet.height, &bytes)
    }

    fn corner(&self, index: usize) -> (u32, u32) {
        let (width, height) = self.cell.unwrap_or((0, 0));
        let index = index as u32;
        (
            (index % self.columns) * width,
            (index / self.columns) * height,
        )
    }
}

/// `image` box-filtered to `width` × `height`; transparent black for an
/// empty or malformed image.
fn thumbnail(image: &Image, width: u32, height: u32) -> Image {
    let mut thumbnail = Image::filled(width, height, Vec4::ZERO);
    if image.width == 0 || image.height == 0 || !image.has_consistent_size() {
        return thumbnail;
    }
    for y in 0..height {
        let (y0, y1) = footprint(y, height, image.height);
        for x in 0..width {
            let (x0, x1) = footprint(x, width, image.width);
            let mut sum = Vec4::ZERO;
            for sy in y0..y1 {
                for sx in x0..x1 {
                    sum += image.pixel(sx, sy);
                }
            }
            let count = ((y1 - y0) * (x1 - x0)) as f32;
            thumbnail.pixels[(y * width + x) as usize] = sum / count;
        }
    }
    thumbnail
}

/// Source pixels `[start, end)` under thumbnail pixel `index` when `source`
/// pixels shrink to `target`; never empty, so enlarging repeats pixels.
fn footprint(index: u32, target: u32, source: u32) -> (u32, u32) {
    let (index, target, source) = (u64::from(index), u64::from(target), u64::from(source));
    let start = index * source / target;
    let end = ((index + 1) * source).div_ceil(target).max(start + 1);
    (start as u32, end.min(source) as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(width: u32, height: u32, value: f32) -> Image {
        Image::filled(width, height, Vec4::splat(value))
    }

    fn sheet_of(images: &[Image], columns: u32, every: u32) -> ContactSheet {
        let mut sheet = ContactSheet::new(columns, every);
        for (index, image) in images.iter().enumerate() {
            sheet.add(index, 100 + index as u32, image);
        }
        sheet
    }

    #[test]
    fn lays_out_a_grid_of_thumbnails() {
        let images: Vec<Image> = (0..5).map(|i| flat(8, 4, i as f32)).collect();
        let sheet = sheet_of(&images, 2, 1).image();
        assert_eq!((sheet.width, sheet.height), (8, 6));
        assert_eq!(sheet.pixel(0, 0), Vec4::splat(0.0));
        assert_eq!(sheet.pixel(4, 0), Vec4::splat(1.0));
        assert_eq!(sheet.pixel(3, 3), Vec4::splat(2.0));
        assert_eq!(sheet.pixel(7, 3), Vec4::splat(3.0));
        assert_eq!(sheet.pixel(0, 5), Vec4::splat(4.0));
        // The empty cell after the last image stays transparent.
        assert_eq!(sheet.pixel(7, 5), Vec4::ZERO);
    }

    #[test]
    fn sizes_and_grids_for_one_seven_and_240_frames() {
        for (frames, columns, every, size) in [
            (1, 6, 1, (160, 90)),
            (7, 6, 1, (960, 180)),
            (7, 3, 1, (960, 540)),
            (240, 6, 1, (960, 40 * 90)),
            (240, 6, 10, (960, 4 * 90)),
        ] {
            let images: Vec<Image> = (0..frames).map(|_| flat(960, 540, 1.0)).collect();
            let sheet = sheet_of(&images, columns, every).image();
            assert_eq!((sheet.width, sheet.height), size, "{frames} frames");
        }
    }

    #[test]
    fn every_kth_frame_is_kept_in_order() {
        let images: Vec<Image> = (0..7).map(|i| flat(4, 4, i as f32)).collect();
        let sheet = sheet_of(&images, 4, 3);
        let kept: Vec<u32> = sheet.thumbnails.iter().map(|(frame, _)| *frame).collect();
        assert_eq!(kept, [100, 103, 106]);
        assert_eq!(sheet.image().pixel(1, 0), Vec4::splat(3.0));
    }

    #[test]
    fn frames_added_out_of_order_take_their_place() {
        let mut sheet = ContactSheet::new(4, 1);
        for (index, frame) in [(0, 7), (1, 3), (2, 5)] {
            sheet.add(index, frame, &flat(4, 4, frame as f32));
        }
        let kept: Vec<u32> = sheet.thumbnails.iter().map(|(frame, _)| *frame).collect();
        assert_eq!(kept, [3, 5, 7]);
        assert_eq!(sheet.image().pixel(0, 0), Vec4::splat(3.0));
    }

    #[test]
    fn box_filter_averages_the_footprint() {
        // A 4x2 checker of 0 and 1 shrinks by 2 to a 2x1 of 0.5.
        let mut image = flat(4, 2, 0.0);
        for (i, p) in image.pixels.iter_mut().enumerate() {
            *p = Vec4::splat(((i + i / 4) % 2) as f32);
        }
        let sheet = sheet_of(&[image], 2, 1).image();
        assert_eq!((sheet.width, sheet.height), (2, 1));
        assert!(sheet.pixels.iter().all(|&p| p == Vec4::splat(0.5)));
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        assert_eq!(sheet_of(&[], 3, 1).image().pixels.len(), 0);
        let tiny = sheet_of(&[flat(1, 1, 2.0), flat(0, 0, 1.0)], 0, 0).image();
        assert_eq!((tiny.width, tiny.height), (1, 2));
        assert_eq!(tiny.pixel(0, 0), Vec4::splat(2.0));
        // A larger second image is filtered into the first image's cell size.
        let mixed = sheet_of(&[flat(4, 4, 1.0), flat(40, 40, 3.0)], 2, 1).image();
        assert_eq!((mixed.width, mixed.height), (4, 2));
        assert_eq!(mixed.pixel(3, 1), Vec4::splat(3.0));
    }

    #[test]
    fn labels_mark_the_sheet_and_the_write_is_whole() {
        let dir = tempfile::tempdir().expect("tempdir");
        let images: Vec<Image> = (0..3).map(|_| flat(240, 120, 0.2)).collect();
        let sheet = sheet_of(&images, 3, 1);
        let path = dir.path().join("sheet.png");
        sheet.write(&path, 0.0).expect("write");
        let written = image::open(&path).expect("read").to_rgba8();
        assert_eq!(written.dimensions(), (240, 40));
        let plain = preview_bytes(&sheet.image(), 0.0);
        let differs = |x0: u32, x1: u32| {
            (0..40).any(|y| {
                (x0..x1).any(|x| {
                    let at = 4 * (y * 240 + x) as usize;
                    written.as_raw()[at..at + 3] != plain[at..at + 3]
                })
            })
        };
        // Each cell's label changed pixels in its top-left corner, and the
        // rest of the cell is the picture.
        for cell in 0..3 {
            assert!(
                differs(cell * 80, cell * 80 + 30),
                "no label in cell {cell}"
            );
            assert!(
                !differs(cell * 80 + 60, cell * 80 + 80),
                "cell {cell} marked beyond its label"
            );
        }
        // Written atomically: no temporary file is left beside the sheet.
        let names: Vec<_> = std::fs::read_dir(dir.path()).expect("dir").collect();
        assert_eq!(names.len(), 1);
    }
}
