//! Recorded hashes of the first frame of every sample scene under every CPU
//! method, at a small size: a speed change must leave every image the same
//! bits (it is how speed work proves that it changed nothing else), and a
//! change that means to alter images shows here which ones it did.
//!
//! After a change that is meant to alter images, record the new hashes with
//! `LMANIM_RECORD_FRAME_HASHES=1 cargo test --test frame_hashes` and commit
//! `tests/frame_hashes.txt` with the change.

mod common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use lmanim::lightmesh::penumbra::Penumbra;
use lmanim::output::Image;
use lmanim::settings::{Method, Settings};

/// The scenes of `animations/`, with their settings file where they have one.
const SCENES: [&str; 6] = [
    "city",
    "courtyard",
    "study-box",
    "study-leaves",
    "study-street",
    "study-wall",
];

/// The methods and variants hashed: every CPU method with the default
/// penumbra, and LMM1 under each other way of sizing one.
const VARIANTS: [(&str, Method, Penumbra); 7] = [
    ("auto", Method::Auto, Penumbra::Wide),
    ("whitted", Method::Whitted, Penumbra::Wide),
    ("lmm", Method::Lmm, Penumbra::Wide),
    ("lmm1", Method::Lmm1, Penumbra::Wide),
    ("lmm1-blocker", Method::Lmm1, Penumbra::Blocker),
    ("lmm1-fixed", Method::Lmm1, Penumbra::Fixed),
    ("area", Method::Area, Penumbra::Wide),
];

fn animations() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("animations")
}

fn recorded_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/frame_hashes.txt")
}

/// The scene's own settings (as `lmanim` would read them) at 128×72.
fn settings_for(scene: &str, method: Method, penumbra: Penumbra) -> Settings {
    let ron = animations().join(format!("{scene}.ron"));
    let mut settings = match ron.exists() {
        true => Settings::load(&ron).expect("the sample's settings load"),
        false => Settings::default(),
    };
    settings.width = 128;
    settings.height = 72;
    settings.method = method;
    settings.spp = 4;
    settings.lightmesh.penumbra = penumbra;
    settings
}

/// FNV-1a over every channel's bits: stable across Rust versions and
/// platforms, unlike `std`'s hasher.
fn image_hash(image: &Image) -> u64 {
    let bytes = image
        .pixels
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(|c| c.to_bits().to_le_bytes());
    bytes.fold(0xcbf2_9ce4_8422_2325, |hash, byte| {
        (hash ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// One line per scene and variant: `scene variant hash`.
fn current_hashes() -> String {
    let mut lines = String::new();
    for scene in SCENES {
        let desc = lmanim::import::load(&animations().join(format!("{scene}.gltf")))
            .expect("the sample imports");
        for (name, method, penumbra) in VARIANTS {
            let image = common::render(desc.clone(), &settings_for(scene, method, penumbra));
            writeln!(lines, "{scene} {name} {:016x}", image_hash(&image)).expect("to a string");
        }
    }
    lines
}

#[test]
fn every_sample_frame_keeps_its_recorded_bits() {
    let current = current_hashes();
    if std::env::var_os("LMANIM_RECORD_FRAME_HASHES").is_some() {
        std::fs::write(recorded_path(), &current).expect("recorded hashes written");
        return;
    }
    let recorded = std::fs::read_to_string(recorded_path()).expect("tests/frame_hashes.txt");
    let changed: Vec<String> = current
        .lines()
        .zip(recorded.lines())
        .filter(|(now, then)| now != then)
        .map(|(now, then)| format!("  recorded {then}, now {now}"))
        .collect();
    assert!(
        changed.is_empty() && current.lines().count() == recorded.lines().count(),
        "frames changed ({} of {} lines):\n{}\n(if the change is meant, record again: \
         LMANIM_RECORD_FRAME_HASHES=1 cargo test --test frame_hashes)",
        changed.len(),
        recorded.lines().count(),
        changed.join("\n")
    );
}

#[test]
fn the_hash_sees_a_single_bit() {
    let mut image = Image::filled(2, 2, glam::Vec4::ONE);
    let before = image_hash(&image);
    image.pixels[3].w = f32::from_bits(image.pixels[3].w.to_bits() ^ 1);
    assert_ne!(before, image_hash(&image));
}
