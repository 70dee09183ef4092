//! Fuzzing the importer: valid files (the corpus below, built by the test
//! support code and the committed `animations/courtyard.gltf`) mutated
//! where it hurts, in glTF's structure rather than at random bytes alone:
//! a value replaced by a boundary number (-1, 2³², 1e39), an index one
//! past its array, another enumeration's name, a wrong media type, an
//! empty object; a key removed; an array element duplicated; then a
//! byte or two flipped in the file as written, `.gltf` or `.glb`.
//!
//! Whatever the mutation, import must give a scene or one line of error,
//! never a panic (which `import::load` would report as `Fault::Panic`).
//! A failing case is shrunk by proptest and its file kept under
//! `target/fuzz-crashes/`, to be committed under `tests/import_regressions/`
//! (which `import_regressions.rs` replays).
//!
//! CI runs a bounded number of mutations (`LMANIM_FUZZ_CASES`, default
//! 4000, a few seconds); BENCHMARKS.md has the figures of a long run.

mod anim_support;
mod import_support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestError, TestRunner};
use serde_json::{json, Value};

use import_support::{glb, one_triangle_document, Bin};

/// A valid file to mutate: its JSON and, for a .glb, its BIN chunk.
struct Seed {
    json: Value,
    bin: Option<Vec<u8>>,
}

fn seeds(dir: &Path) -> Vec<Seed> {
    let from_gltf = |path: PathBuf| Seed {
        json: serde_json::from_slice(&std::fs::read(path).expect("read seed")).expect("JSON"),
        bin: None,
    };
    let courtyard = Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/courtyard.gltf");
    vec![
        strip_glb(dir),
        from_gltf(anim_support::skinned(dir)),
        from_gltf(anim_support::morph(dir)),
        from_gltf(anim_support::pointers(dir)),
        from_gltf(anim_support::interpolations(dir)),
        from_gltf(courtyard),
    ]
}

/// A textured, indexed triangle strip under a parent node, as a .glb with
/// its buffer in the BIN chunk.
fn strip_glb(dir: &Path) -> Seed {
    let mut bin = Bin::default();
    let positions = bin.vec3(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ]);
    let normals = bin.vec3(&[[0.0, 0.0, 1.0]; 4]);
    let uvs = bin.vec2(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]);
    let indices = bin.indices_u16(&[0, 1, 2, 3]);
    let mut doc = one_triangle_document(json!({
        "attributes": { "POSITION": positions, "NORMAL": normals, "TEXCOORD_0": uvs },
        "indices": indices, "mode": 5, "material": 0 }));
    doc["nodes"] = json!([{ "children": [1], "translation": [1.0, 2.0, 3.0] },
        { "mesh": 0, "camera": 0 }]);
    doc["materials"] = json!([{ "pbrMetallicRoughness": { "baseColorFactor": [1, 0.5, 0.2, 1] } }]);
    doc["cameras"] =
        json!([{ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1 } }]);
    let bytes = std::fs::read(bin.write_glb(doc, dir, "strip.glb")).expect("read seed");
    let chunk = |at: usize| {
        let length = u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes")) as usize;
        (&bytes[at + 8..at + 8 + length], at + 8 + length)
    };
    let (json_chunk, next) = chunk(12);
    let (bin_chunk, _) = chunk(next);
    Seed {
        json: serde_json::from_slice(json_chunk).expect("JSON chunk"),
        bin: Some(bin_chunk.to_vec()),
    }
}

/// One change to the JSON tree; `at` picks a value (modulo how many the
/// tree has, in document order), `with` a replacement.
#[derive(Clone, Debug)]
enum Edit {
    Replace { at: usize, with: usize },
    Remove { at: usize },
    Duplicate { at: usize },
}

/// One fuzz case: a seed, the edits to its JSON, whether it is written
/// as .glb, and bytes to overwrite in the written file.
#[derive(Clone, Debug)]
struct Mutation {
    seed: usize,
    glb: bool,
    edits: Vec<Edit>,
    bytes: Vec<(usize, u8)>,
}

fn mutation(seeds: usize) -> impl Strategy<Value = Mutation> {
    let edit = prop_oneof![
        4 => (any::<usize>(), any::<usize>()).prop_map(|(at, with)| Edit::Replace { at, with }),
        1 => any::<usize>().prop_map(|at| Edit::Remove { at }),
        1 => any::<usize>().prop_map(|at| Edit::Duplicate { at }),
    ];
    (
        0..seeds,
        any::<bool>(),
        prop::collection::vec(edit, 0..4),
        // Most cases keep the JSON well-formed, to reach past the parser.
        prop_oneof![
            3 => Just(Vec::new()),
            1 => prop::collection::vec((any::<usize>(), any::<u8>()), 1..3),
        ],
    )
        .prop_map(|(seed, glb, edits, bytes)| Mutation {
            seed,
            glb,
            edits,
            bytes,
        })
}

/// Values a hostile file puts where a valid one has something else: the
/// edges of the integer types glTF uses, non-finite-to-f32 numbers, other
/// enumerations' names, media types and paths that must be refused.
fn replacements(original: &Value) -> Vec<Value> {
    let mut values = vec![
        json!(-1),
        json!(0),
        json!(1),
        json!(3),
        json!(4),
        json!(255),
        json!(65535),
        json!(4_294_967_295u64),
        json!(4_294_967_296u64),
        json!(u64::MAX),
        json!(0.5),
        json!(-0.5),
        json!(1e39),
        json!(null),
        json!(true),
        json!(""),
        json!([]),
        json!({}),
        json!([0.0, 0.0, 0.0, 0.0]),
        json!("translation"),
        json!("rotation"),
        json!("weights"),
        json!("pointer"),
        json!("SCALAR"),
        json!("VEC4"),
        json!("MAT4"),
        json!("STEP"),
        json!("CUBICSPLINE"),
        json!("orthographic"),
        json!("spot"),
        json!("1.0"),
        json!("2.1"),
        json!("data:text/plain;base64,AAAA"),
        json!("data:application/octet-stream;base64,"),
        json!("../outside.bin"),
        json!("/nodes/0/rotation"),
    ];
    // Near the original, where off-by-one faults live.
    if let Some(number) = original.as_i64() {
        values.extend([json!(number + 1), json!(number - 1), json!(number * 2)]);
    }
    values
}

/// The JSON pointers of every value in `document`, in document order.
fn pointers(document: &Value) -> Vec<String> {
    fn walk(value: &Value, at: String, out: &mut Vec<String>) {
        match value {
            Value::Object(map) => {
                for (key, child) in map {
                    let key = key.replace('~', "~0").replace('/', "~1");
                    walk(child, format!("{at}/{key}"), out);
                }
            }
            Value::Array(items) => {
                for (index, child) in items.iter().enumerate() {
                    walk(child, format!("{at}/{index}"), out);
                }
            }
            _ => {}
        }
        out.push(at);
    }
    let mut out = Vec::new();
    walk(document, String::new(), &mut out);
    out
}

fn apply(document: &mut Value, edit: &Edit) {
    let pointers = pointers(document);
    let pick = |at: usize| pointers[at % pointers.len()].clone();
    match *edit {
        Edit::Replace { at, with } => {
            let at = pick(at);
            if let Some(value) = document.pointer_mut(&at) {
                let choices = replacements(value);
                *value = choices[with % choices.len()].clone();
            }
        }
        Edit::Remove { at } | Edit::Duplicate { at } => {
            let at = pick(at);
            let Some((parent, last)) = at.rsplit_once('/') else {
                return; // the root
            };
            match document.pointer_mut(parent) {
                Some(Value::Object(map)) => {
                    let key = last.replace("~1", "/").replace("~0", "~");
                    if matches!(edit, Edit::Remove { .. }) {
                        map.remove(&key);
                    }
                }
                Some(Value::Array(items)) => {
                    let index: usize = last.parse().expect("array index");
                    if matches!(edit, Edit::Remove { .. }) {
                        items.remove(index);
                    } else {
                        let copy = items[index].clone();
                        items.insert(index, copy);
                    }
                }
                _ => {}
            }
        }
    }
}

/// The file `mutation` makes of its seed.
fn file_bytes(seed: &Seed, mutation: &Mutation) -> Vec<u8> {
    let mut document = seed.json.clone();
    for edit in &mutation.edits {
        apply(&mut document, edit);
    }
    let json = serde_json::to_vec(&document).expect("JSON");
    let mut bytes = if mutation.glb {
        glb(&json, seed.bin.as_deref().unwrap_or_default())
    } else {
        json
    };
    for &(at, byte) in &mutation.bytes {
        let length = bytes.len();
        bytes[at % length] = byte;
    }
    bytes
}

/// What an import came to, coarsely: `Ok`, or the fault's kind and, for
/// a broken rule, its JSON path without indices. Counting the kinds seen
/// says how much of the importer's refusals the mutations reach.
fn outcome_kind(result: &Result<lmanim::scene::SceneDesc, lmanim::import::ImportError>) -> String {
    let Err(error) = result else {
        return "Ok".to_owned();
    };
    let debug = format!("{:?}", error.fault);
    let variant: String = debug.chars().take_while(|c| c.is_alphanumeric()).collect();
    if variant != "Rule" {
        return variant;
    }
    // A rule's message starts with its JSON path.
    let message = error.fault.to_string();
    let path = message.split(": ").next().unwrap_or_default();
    let shape: String = path.chars().filter(|c| !c.is_ascii_digit()).collect();
    format!("{variant} {shape}")
}

/// The generator's seed: fixed, so that CI is reproducible, unless
/// `LMANIM_FUZZ_SEED` asks for another (a long run tries several).
fn seed() -> u64 {
    std::env::var("LMANIM_FUZZ_SEED")
        .ok()
        .and_then(|text| text.parse().ok())
        .unwrap_or(0x6c6d_616e_696d)
}

fn cases() -> u32 {
    std::env::var("LMANIM_FUZZ_CASES")
        .ok()
        .and_then(|text| text.parse().ok())
        .unwrap_or(4000)
}

#[test]
fn mutated_files_never_make_import_panic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let seeds = seeds(dir.path());
    let crashes = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-crashes");
    let outcomes = Mutex::new(BTreeMap::<String, usize>::new());
    let started = std::time::Instant::now();
    let mut runner = TestRunner::new(Config {
        cases: cases(),
        rng_seed: RngSeed::Fixed(seed()),
        failure_persistence: None,
        ..Config::default()
    });
    let result = runner.run(&mutation(seeds.len()), |mutation| {
        let extension = if mutation.glb { "glb" } else { "gltf" };
        let path = dir.path().join(format!("case.{extension}"));
        let bytes = file_bytes(&seeds[mutation.seed], &mutation);
        std::fs::write(&path, &bytes).expect("write case");
        let result = lmanim::import::load(&path);
        *outcomes
            .lock()
            .expect("not poisoned")
            .entry(outcome_kind(&result))
            .or_default() += 1;
        if let Err(error) = &result {
            let message = error.to_string();
            prop_assert!(
                !matches!(error.fault, lmanim::import::Fault::Panic(_)),
                "{}",
                message
            );
            prop_assert_eq!(message.lines().count(), 1, "{}", message);
        }
        Ok(())
    });
    let outcomes = outcomes.into_inner().expect("not poisoned");
    let executions: usize = outcomes.values().sum();
    println!(
        "seed {}: {executions} executions in {:.1} s, {} outcome kinds:",
        seed(),
        started.elapsed().as_secs_f64(),
        outcomes.len()
    );
    for (kind, count) in &outcomes {
        println!("  {count:6}  {kind}");
    }
    if let Err(failure) = result {
        // The shrunk case, as a file to keep under tests/import_regressions/.
        if let TestError::Fail(_, mutation) = &failure {
            let extension = if mutation.glb { "glb" } else { "gltf" };
            let bytes = file_bytes(&seeds[mutation.seed], mutation);
            std::fs::create_dir_all(&crashes).expect("crash folder");
            let kept = crashes.join(format!("crash-{:016x}.{extension}", fingerprint(&bytes)));
            std::fs::write(&kept, &bytes).expect("keep the crash");
            println!("the smallest failing file is kept as {}", kept.display());
        }
        panic!("{failure}");
    }
    // The mutations reach deep: past the JSON, into references, data and
    // animation, not only the container and the parser.
    for deep in ["Ok", "Invalid", "AccessorType", "Animation"] {
        assert!(
            outcomes.contains_key(deep),
            "no case reached {deep}: {outcomes:?}"
        );
    }
}

/// FNV-1a of the file, to name a kept crash.
fn fingerprint(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |hash, &byte| {
        (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3)
    })
}
