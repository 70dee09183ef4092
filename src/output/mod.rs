//! The end of a frame's data flow: rendered [`Image`]s become files (and
//! EXRs of any common layout are read back, `exr_read.rs`). EXR
//! frames hold linear radiance (half floats by default), PNG previews are
//! tone-mapped and sRGB-encoded, frame names come from a `#` pattern, and
//! storyboards get a contact sheet. Frames are written on a thread of
//! their own while the next renders. Every file is written atomically, so a
//! crashed or killed render never leaves a half-written frame behind.

mod atomic;
mod background;
mod contact_sheet;
mod error;
mod existing;
mod exr;
mod exr_read;
mod label;
mod pattern;
mod png;
mod shot_sheet;

pub use atomic::write_atomically;
pub use background::{BackgroundWriter, FrameFiles};
pub use contact_sheet::ContactSheet;
pub use error::OutputError;
pub use existing::frame_on_disk;
pub use exr::{write_exr, write_layered_exr};
pub use exr_read::{read_exr, read_exr_picture, ExrChannels, ExrPicture};
pub use label::FONT;
pub use pattern::FramePattern;
pub use png::{tone_map, write_png_preview, write_srgb_png};
pub use shot_sheet::ShotSheet;

use glam::Vec4;

/// A rendered frame: linear Rec.709 RGBA, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec4>,
}

impl Image {
    /// An image of one colour, e.g. the background of a contact sheet.
    pub fn filled(width: u32, height: u32, colour: Vec4) -> Image {
        Image {
            width,
            height,
            pixels: vec![colour; width as usize * height as usize],
        }
    }

    /// The pixel at column `x`, row `y` (row 0 is the top).
    ///
    /// # Panics
    /// When `(x, y)` lies outside the image: callers index in bounds.
    pub fn pixel(&self, x: u32, y: u32) -> Vec4 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Whether `pixels` holds exactly `width * height` values; writers check
    /// this before touching the disk so a bad buffer is a clear error, not a
    /// panic halfway through an encoder.
    fn has_consistent_size(&self) -> bool {
        self.pixels.len() as u64 == u64::from(self.width) * u64::from(self.height)
    }
}

/// One layer of arbitrary output variables (AOVs) of a frame: named EXR
/// channels, each pixel's values together, row-major like [`Image`].
#[derive(Clone, Debug, PartialEq)]
pub struct AovLayer {
    /// Full channel names, e.g. `light.Lamp.R` or `Z`.
    pub channels: Vec<String>,
    /// `channels.len()` values per pixel.
    pub values: Vec<f32>,
}

/// What a backend renders of a frame: the beauty, and the AOV layers the
/// run asked for (none by default).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderedFrame {
    pub image: Image,
    pub aovs: Vec<AovLayer>,
}

impl From<Image> for RenderedFrame {
    fn from(image: Image) -> RenderedFrame {
        RenderedFrame {
            image,
            aovs: Vec::new(),
        }
    }
}

/// Sample type of the EXR channels. Half keeps frames small and holds the
/// whole range a render produces (up to 65504, ~3 significant digits); Float
/// is for references that tests compare against exactly.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum ExrPrecision {
    #[default]
    Half,
    Float,
}
