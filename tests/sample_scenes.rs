//! The sample scenes under `animations/` are what `cargo run --example
//! make_animations` writes today, byte for byte: the committed files and
//! the generator that made them cannot drift apart unnoticed.

use std::path::Path;

use lmanim_authoring::samples::SAMPLES;

#[test]
fn regenerating_the_samples_reproduces_the_committed_files() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("animations");
    for sample in &SAMPLES {
        let generated = (sample.build)()
            .expect("the sample builds")
            .to_embedded_json()
            .to_string();
        let committed = std::fs::read_to_string(dir.join(sample.file_name)).expect("committed");
        // Where they differ, if they do: the first differing byte and what
        // surrounds it, rather than two 400 kB strings.
        let first_difference = generated
            .bytes()
            .zip(committed.bytes())
            .position(|(a, b)| a != b)
            .unwrap_or(generated.len().min(committed.len()));
        let around = |text: &str| {
            let start = first_difference.saturating_sub(60);
            text.get(start..(first_difference + 60).min(text.len()))
                .unwrap_or_default()
                .to_owned()
        };
        assert!(
            generated == committed,
            "{}: generated {} bytes, committed {}; first difference at byte {first_difference}:\n\
             generated …{}…\ncommitted …{}…\n(run `cargo run --example make_animations` if the change is meant)",
            sample.file_name,
            generated.len(),
            committed.len(),
            around(&generated),
            around(&committed)
        );
    }
}
