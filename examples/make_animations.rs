//! Writes the sample scenes under `animations/` (see
//! [`lmanim_authoring::samples`]): `cargo run --example make_animations`.

use std::path::Path;

use anyhow::Context;
use lmanim_authoring::samples::SAMPLES;

fn main() -> anyhow::Result<()> {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("animations");
    for sample in &SAMPLES {
        let path = out.join(sample.file_name);
        (sample.build)()
            .and_then(|builder| builder.write_gltf(&path))
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
