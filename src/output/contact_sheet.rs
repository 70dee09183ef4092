//! Contact sheets: many frames as thumbnails on one image, for storyboard
//! previews of a shot. The sheet is about as wide as one frame.

use glam::Vec4;

use super::Image;

/// Lays `images` out left to right, top to bottom, `columns` to a row.
/// Each thumbnail is the first image's size divided by `columns` (at least
/// one pixel), box-filtered: every thumbnail pixel is the mean of the source
/// pixels under it. Cells of empty or malformed images, and the rest of the
/// last row, stay transparent black. No images give a 0×0 sheet; `columns`
/// 0 counts as 1.
pub fn contact_sheet(images: &[Image], columns: u32) -> Image {
    let Some(first) = images.first() else {
        return Image::filled(0, 0, Vec4::ZERO);
    };
    let columns = columns.max(1);
    let cell_width = (first.width / columns).max(1);
    let cell_height = (first.height / columns).max(1);
    let used_columns = columns.min(images.len() as u32);
    let rows = (images.len() as u32).div_ceil(columns);
    let mut sheet = Image::filled(used_columns * cell_width, rows * cell_height, Vec4::ZERO);
    for (index, image) in images.iter().enumerate() {
        if image.width == 0 || image.height == 0 || !image.has_consistent_size() {
            continue;
        }
        let index = index as u32;
        let left = (index % columns) * cell_width;
        let top = (index / columns) * cell_height;
        for y in 0..cell_height {
            let (y0, y1) = footprint(y, cell_height, image.height);
            for x in 0..cell_width {
                let (x0, x1) = footprint(x, cell_width, image.width);
                let mut sum = Vec4::ZERO;
                for sy in y0..y1 {
                    for sx in x0..x1 {
                        sum += image.pixel(sx, sy);
                    }
                }
                let count = ((y1 - y0) * (x1 - x0)) as f32;
                let at = (top + y) as usize * sheet.width as usize + (left + x) as usize;
                sheet.pixels[at] = sum / count;
            }
        }
    }
    sheet
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

    #[test]
    fn lays_out_a_grid_of_thumbnails() {
        let images: Vec<Image> = (0..5).map(|i| flat(8, 4, i as f32)).collect();
        let sheet = contact_sheet(&images, 2);
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
    fn box_filter_averages_the_footprint() {
        // A 4x2 checker of 0 and 1 shrinks by 2 to a 2x1 of 0.5.
        let mut image = flat(4, 2, 0.0);
        for (i, p) in image.pixels.iter_mut().enumerate() {
            *p = Vec4::splat(((i + i / 4) % 2) as f32);
        }
        let sheet = contact_sheet(&[image], 2);
        assert_eq!((sheet.width, sheet.height), (2, 1));
        assert!(sheet.pixels.iter().all(|&p| p == Vec4::splat(0.5)));
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        assert_eq!(contact_sheet(&[], 3).pixels.len(), 0);
        let tiny = contact_sheet(&[flat(1, 1, 2.0), flat(0, 0, 1.0)], 0);
        assert_eq!((tiny.width, tiny.height), (1, 2));
        assert_eq!(tiny.pixel(0, 0), Vec4::splat(2.0));
        // A larger second image is filtered into the first image's cell size.
        let mixed = contact_sheet(&[flat(4, 4, 1.0), flat(40, 40, 3.0)], 2);
        assert_eq!((mixed.width, mixed.height), (4, 2));
        assert_eq!(mixed.pixel(3, 1), Vec4::splat(3.0));
    }
}
