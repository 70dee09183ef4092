//! Contact sheets: a shot's frames as labelled thumbnails on one PNG, for
//! storyboard previews. Frames are shrunk as they are rendered (or read
//! back from disk, `shot_sheet.rs`), so a long shot holds thumbnails, not
//! frames. Thumbnails have a width of their own, large enough to judge a
//! shot by (a storyboard is read at a few hundred pixels), and the sheet
//! grows a row at a time with the frames, up to [`MAX_SHEET_SIDE`] and
//! [`MAX_SHEET_PIXELS`]; it is tone-mapped like the previews, each
//! thumbnail labelled with its frame number, in frame order, and written
//! once, atomically, at the end of the run.

use std::path::Path;

use glam::Vec4;

use super::label::{draw_label, label_font, Canvas};
use super::png::{preview_bytes, write_rgba8};
use super::{Image, OutputError};

/// Thumbnail width when none is asked for (or the frame's width, when
/// smaller): a few hundred pixels, the size a storyboard is read at.
pub const DEFAULT_THUMB_WIDTH: u32 = 256;

/// The longest side of a sheet: what PNG viewers and browsers still open.
pub const MAX_SHEET_SIDE: u32 = 16384;

/// The most pixels on a sheet (32 Mi, 512 MiB while it is composed in
/// linear light): a long shot's sheet stays within a machine's memory.
pub const MAX_SHEET_PIXELS: u64 = 1 << 25;

/// The size of a thumbnail of a `width` × `height` frame: `thumb_width`
/// wide (by default the smaller of [`DEFAULT_THUMB_WIDTH`] and the
/// frame's width), the frame's aspect kept, at least 1×1.
pub fn thumbnail_size(width: u32, height: u32, thumb_width: Option<u32>) -> (u32, u32) {
    let thumb_width = thumb_width.unwrap_or(DEFAULT_THUMB_WIDTH.min(width)).max(1);
    let width = u64::from(width.max(1));
    let thumb_height = (u64::from(height) * u64::from(thumb_width) + width / 2) / width;
    (
        thumb_width,
        thumb_height.clamp(1, u64::from(u32::MAX)) as u32,
    )
}

/// The size of a sheet of `count` thumbnails of size `cell`, `columns` to
/// a row, or why it is too large to write (one line, for the user).
pub fn sheet_size(count: u64, columns: u32, cell: (u32, u32)) -> Result<(u32, u32), String> {
    let columns = u64::from(columns.max(1));
    let width = columns.min(count) * u64::from(cell.0);
    let height = count.div_ceil(columns) * u64::from(cell.1);
    let side = u64::from(MAX_SHEET_SIDE);
    if width > side || height > side || width * height > MAX_SHEET_PIXELS {
        return Err(format!(
            "the contact sheet of {count} thumbnails of {}x{} in {columns} columns would be {width}x{height} pixels, over the bound of {MAX_SHEET_SIDE} a side and {MAX_SHEET_PIXELS} pixels: raise --sheet-every or --sheet-columns, or lower --sheet-thumb-width",
            cell.0, cell.1
        ));
    }
    Ok((width as u32, height as u32))
}

/// A sheet being filled: every `every`-th frame of a run, `columns` to a
/// row.
pub struct ContactSheet {
    columns: u32,
    every: u32,
    /// Thumbnail width asked for; None: [`thumbnail_size`]'s default.
    thumb_width: Option<u32>,
    /// Thumbnail size, from the first frame.
    cell: Option<(u32, u32)>,
    thumbnails: Vec<(u32, Image)>,
}

impl ContactSheet {
    /// `columns` and `every` of 0 count as 1.
    pub fn new(columns: u32, every: u32, thumb_width: Option<u32>) -> ContactSheet {
        ContactSheet {
            columns: columns.max(1),
            every: every.max(1),
            thumb_width,
            cell: None,
            thumbnails: Vec::new(),
        }
    }

    /// Why a sheet over `frames` frames of `width` × `height` would be
    /// too large to write, if it would: known before the first frame
    /// renders, so a long render does not end in a refusal.
    pub fn fits(&self, frames: usize, (width, height): (u32, u32)) -> Result<(), String> {
        let shown = frames.div_ceil(self.every as usize) as u64;
        let cell = thumbnail_size(width, height, self.thumb_width);
        sheet_size(shown, self.columns, cell).map(|_| ())
    }

    /// Whether the sheet shows the `index`-th frame of its shot.
    pub fn shows(&self, index: usize) -> bool {
        index.is_multiple_of(self.every as usize)
    }

    /// Takes the `index`-th frame of the shot, frame number `frame`, if it
    /// is one the sheet shows, in its place by frame number. Each
    /// thumbnail is the first frame's [`thumbnail_size`], box-filtered:
    /// every thumbnail pixel is the mean of the frame's pixels under it.
    pub fn add(&mut self, index: usize, frame: u32, image: &Image) {
        if !self.shows(index) {
            return;
        }
        let thumb_width = self.thumb_width;
        let (width, height) = *(self.cell)
            .get_or_insert_with(|| thumbnail_size(image.width, image.height, thumb_width));
        let place = self.thumbnails.partition_point(|(shown, _)| *shown < frame);
        (self.thumbnails).insert(place, (frame, thumbnail(image, width, height)));
    }

    /// The sheet: thumbnails left to right, top to bottom; cells after the
    /// last stay transparent black. No frames give a 0×0 sheet; a sheet
    /// over [`sheet_size`]'s bound is refused.
    pub fn image(&self) -> Result<Image, String> {
        let Some((width, height)) = self.cell else {
            return Ok(Image::filled(0, 0, Vec4::ZERO));
        };
        let count = self.thumbnails.len() as u64;
        let (sheet_width, sheet_height) = sheet_size(count, self.columns, (width, height))?;
        let mut sheet = Image::filled(sheet_width, sheet_height, Vec4::ZERO);
        for (index, (_, thumbnail)) in self.thumbnails.iter().enumerate() {
            let (left, top) = self.corner(index);
            for y in 0..height {
                let row = (top + y) as usize * sheet.width as usize + left as usize;
                let source = (y * width) as usize..((y + 1) * width) as usize;
                sheet.pixels[row..row + width as usize].copy_from_slice(&thumbnail.pixels[source]);
            }
        }
        Ok(sheet)
    }

    /// Writes the sheet at `exposure` stops to `path`, atomically, each
    /// thumbnail labelled with its frame number.
    pub fn write(&self, path: &Path, exposure: f32) -> Result<(), OutputError> {
        let sheet = self.image().map_err(|fault| OutputError::Encode {
            path: path.to_path_buf(),
            fault,
        })?;
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

    fn sheet_of(images: &[Image], columns: u32, every: u32, thumb: Option<u32>) -> ContactSheet {
        let mut sheet = ContactSheet::new(columns, every, thumb);
        for (index, image) in images.iter().enumerate() {
            sheet.add(index, 100 + index as u32, image);
        }
        sheet
    }

    #[test]
    fn lays_out_a_grid_of_thumbnails() {
        let images: Vec<Image> = (0..5).map(|i| flat(8, 4, i as f32)).collect();
        let sheet = sheet_of(&images, 2, 1, Some(4)).image().unwrap();
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
        // 256×144 thumbnails of 960×540 frames; the sheet grows.
        for (frames, columns, every, size) in [
            (1, 6, 1, (256, 144)),
            (7, 6, 1, (6 * 256, 2 * 144)),
            (7, 3, 1, (3 * 256, 3 * 144)),
            (240, 6, 1, (6 * 256, 40 * 144)),
            (240, 6, 10, (6 * 256, 4 * 144)),
        ] {
            let images: Vec<Image> = (0..frames).map(|_| flat(960, 540, 1.0)).collect();
            let sheet = sheet_of(&images, columns, every, None).image().unwrap();
            assert_eq!((sheet.width, sheet.height), size, "{frames} frames");
        }
    }

    #[test]
    fn thumbnails_of_a_48_frame_shot_stay_readable() {
        // The preview: 48 frames of 320×180 at the default columns.
        let columns = crate::settings::Settings::default().sheet_columns;
        let images: Vec<Image> = (0..48).map(|_| flat(320, 180, 1.0)).collect();
        let sheet = sheet_of(&images, columns, 1, None);
        let (width, height) = sheet.cell.unwrap();
        assert!(width >= 160, "thumbnails {width} wide");
        assert_eq!((width, height), (256, 144));
        let image = sheet.image().unwrap();
        assert_eq!(
            (image.width, image.height),
            (columns * 256, 48u32.div_ceil(columns) * 144)
        );
    }

    #[test]
    fn thumbnails_are_the_width_asked_for_at_the_frames_aspect() {
        assert_eq!(thumbnail_size(320, 180, None), (256, 144));
        assert_eq!(
            thumbnail_size(100, 50, None),
            (100, 50),
            "never enlarged by default"
        );
        assert_eq!(thumbnail_size(1920, 1080, Some(400)), (400, 225));
        assert_eq!(
            thumbnail_size(100, 50, Some(400)),
            (400, 200),
            "enlarged when asked"
        );
        assert_eq!(
            thumbnail_size(1000, 1, Some(10)),
            (10, 1),
            "at least a pixel high"
        );
    }

    #[test]
    fn a_sheet_over_the_bound_is_refused_in_one_line() {
        assert_eq!(sheet_size(240, 6, (256, 144)), Ok((1536, 40 * 144)));
        // Too tall: 2400 thumbnails in 6 columns.
        let fault = sheet_size(2400, 6, (256, 144)).unwrap_err();
        assert!(
            fault.contains("2400 thumbnails") && fault.contains("1536x57600"),
            "{fault}"
        );
        assert!(
            fault.contains("--sheet-every") && !fault.contains('\n'),
            "{fault}"
        );
        // Within each side, over the pixel budget.
        assert!(sheet_size(64 * 64, 64, (256, 256)).is_err());
        assert!(sheet_size(1, 1, (MAX_SHEET_SIDE + 1, 1)).is_err());
        let sheet = ContactSheet::new(6, 1, None);
        assert!(sheet.fits(240, (1280, 720)).is_ok());
        assert!(sheet.fits(2400, (1280, 720)).is_err());
        assert!(ContactSheet::new(6, 10, None)
            .fits(2400, (1280, 720))
            .is_ok());
    }

    #[test]
    fn every_kth_frame_is_kept_in_order() {
        let images: Vec<Image> = (0..7).map(|i| flat(4, 4, i as f32)).collect();
        let sheet = sheet_of(&images, 4, 3, Some(1));
        let kept: Vec<u32> = sheet.thumbnails.iter().map(|(frame, _)| *frame).collect();
        assert_eq!(kept, [100, 103, 106]);
        assert_eq!(sheet.image().unwrap().pixel(1, 0), Vec4::splat(3.0));
    }

    #[test]
    fn frames_added_out_of_order_take_their_place() {
        let mut sheet = ContactSheet::new(4, 1, None);
        for (index, frame) in [(0, 7), (1, 3), (2, 5)] {
            sheet.add(index, frame, &flat(4, 4, frame as f32));
        }
        let kept: Vec<u32> = sheet.thumbnails.iter().map(|(frame, _)| *frame).collect();
        assert_eq!(kept, [3, 5, 7]);
        assert_eq!(sheet.image().unwrap().pixel(0, 0), Vec4::splat(3.0));
    }

    #[test]
    fn box_filter_averages_the_footprint() {
        // A 4x2 checker of 0 and 1 shrinks by 2 to a 2x1 of 0.5.
        let mut image = flat(4, 2, 0.0);
        for (i, p) in image.pixels.iter_mut().enumerate() {
            *p = Vec4::splat(((i + i / 4) % 2) as f32);
        }
        let sheet = sheet_of(&[image], 2, 1, Some(2)).image().unwrap();
        assert_eq!((sheet.width, sheet.height), (2, 1));
        assert!(sheet.pixels.iter().all(|&p| p == Vec4::splat(0.5)));
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        assert_eq!(sheet_of(&[], 3, 1, None).image().unwrap().pixels.len(), 0);
        let tiny = sheet_of(&[flat(1, 1, 2.0), flat(0, 0, 1.0)], 0, 0, None)
            .image()
            .unwrap();
        assert_eq!((tiny.width, tiny.height), (1, 2));
        assert_eq!(tiny.pixel(0, 0), Vec4::splat(2.0));
        // A larger second image is filtered into the first image's cell size.
        let mixed = sheet_of(&[flat(4, 4, 1.0), flat(40, 40, 3.0)], 2, 1, Some(2))
            .image()
            .unwrap();
        assert_eq!((mixed.width, mixed.height), (4, 2));
        assert_eq!(mixed.pixel(3, 1), Vec4::splat(3.0));
    }

    #[test]
    fn labels_mark_the_sheet_and_the_write_is_whole() {
        let dir = tempfile::tempdir().expect("tempdir");
        let images: Vec<Image> = (0..3).map(|_| flat(240, 120, 0.2)).collect();
        let sheet = sheet_of(&images, 3, 1, Some(80));
        let path = dir.path().join("sheet.png");
        sheet.write(&path, 0.0).expect("write");
        let written = image::open(&path).expect("read").to_rgba8();
        assert_eq!(written.dimensions(), (240, 40));
        let plain = preview_bytes(&sheet.image().unwrap(), 0.0);
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
