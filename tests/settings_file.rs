//! Settings files: defaults, a full file, RON errors with positions, and
//! every validation rule.

use std::path::Path;

use lmanim::output::ExrPrecision;
use lmanim::settings::{Method, Settings, SettingsError};

fn parse(text: &str) -> Result<Settings, SettingsError> {
    Settings::parse(text, Path::new("shot.ron"))
}

#[test]
fn an_empty_file_gives_the_defaults() {
    let settings = parse("()").unwrap();
    assert_eq!(settings, Settings::default());
    assert_eq!((settings.width, settings.height), (640, 360));
    assert_eq!(settings.fps, 24.0);
    assert_eq!(settings.method, Method::Auto);
    assert_eq!((settings.spp, settings.max_depth), (1, 5));
    assert_eq!(settings.exr_precision, ExrPrecision::Half);
    assert_eq!(settings.lightmesh.ki, 2.5);
    settings.validate().unwrap();
}

#[test]
fn a_full_file_sets_every_field() {
    let settings = parse(
        r#"(
            width: 1920, height: 1080, fps: 30.0, method: lmm1, spp: 4,
            max_depth: 8, camera: Some("main"), exr_precision: float,
            png: true, threads: Some(6), out: Some("out/frame.####.exr"),
            lamps: (default_radius: Some(0.1), radius: {"Lamp.001": 0.25}),
            lightmesh: (h: Some(0.05), ki: 3.0),
        )"#,
    )
    .unwrap();
    assert_eq!(settings.width, 1920);
    assert_eq!(settings.method, Method::Lmm1);
    assert_eq!(settings.camera.as_deref(), Some("main"));
    assert_eq!(settings.exr_precision, ExrPrecision::Float);
    assert!(settings.png);
    assert_eq!(settings.threads, Some(6));
    assert_eq!(settings.lamps.radius["Lamp.001"], 0.25);
    assert_eq!(settings.lightmesh.h, Some(0.05));
    settings.validate().unwrap();
    // Writing and reading back gives the same settings.
    let text = ron::to_string(&settings).unwrap();
    assert_eq!(parse(&text).unwrap(), settings);
}

#[test]
fn an_unknown_field_is_an_error_with_its_position() {
    let error = parse("(\n  width: 10,\n  hieght: 20,\n)").unwrap_err();
    let message = error.to_string();
    assert!(message.starts_with("shot.ron:3:"), "{message}");
    assert!(message.contains("hieght"), "{message}");
}

#[test]
fn a_type_error_names_file_and_line() {
    let message = parse("(width: \"wide\")").unwrap_err().to_string();
    assert!(message.starts_with("shot.ron:1:"), "{message}");
    let message = parse("(method: fast)").unwrap_err().to_string();
    assert!(message.contains("fast"), "{message}");
}

#[test]
fn load_reads_a_file_and_names_it_in_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.ron");
    std::fs::write(&path, "(spp: 0)").unwrap();
    let message = Settings::load(&path).unwrap_err().to_string();
    assert!(
        message.contains("bad.ron") && message.contains("spp"),
        "{message}"
    );
    let missing = Settings::load(&dir.path().join("none.ron")).unwrap_err();
    assert!(missing.to_string().contains("none.ron"));
    std::fs::write(&path, "(width: 8, height: 8)").unwrap();
    assert_eq!(Settings::load(&path).unwrap().width, 8);
}

#[test]
fn the_sample_settings_load() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/courtyard.ron");
    let settings = Settings::load(&path).unwrap();
    assert_eq!((settings.width, settings.height), (640, 360));
    assert!(!settings.lamps.radius.is_empty());
}

#[test]
fn method_names_match_between_ron_cli_and_display() {
    use clap::ValueEnum;
    for method in Method::value_variants() {
        let name = method.to_string();
        let cli = method.to_possible_value().unwrap();
        assert_eq!(cli.get_name(), name);
        let parsed = parse(&format!("(method: {name})")).unwrap();
        assert_eq!(parsed.method, *method);
    }
}

/// Breaks one validation rule of a default `Settings`.
type BreakRule = fn(&mut Settings);

/// Each case breaks one rule; the message must name the field.
#[test]
fn impossible_values_are_rejected() {
    let cases: [(&str, BreakRule); 24] = [
        ("width", |s| s.width = 0),
        ("width", |s| s.width = 32769),
        ("height", |s| s.height = 0),
        ("height", |s| s.height = 40000),
        ("spp", |s| s.spp = 0),
        ("fps", |s| s.fps = 0.0),
        ("fps", |s| s.fps = -24.0),
        ("fps", |s| s.fps = f64::NAN),
        ("fps", |s| s.fps = f64::INFINITY),
        ("max_depth", |s| s.max_depth = 65),
        ("lightmesh.ki", |s| s.lightmesh.ki = 0.0),
        ("lightmesh.ki", |s| s.lightmesh.ki = f32::NAN),
        ("lightmesh.ki", |s| s.lightmesh.ki = 8.5),
        ("lightmesh.h", |s| s.lightmesh.h = Some(-1.0)),
        ("lightmesh.h", |s| s.lightmesh.h = Some(0.0)),
        ("lightmesh.h", |s| s.lightmesh.h = Some(f32::INFINITY)),
        ("lightmesh.gpu_memory_mib", |s| {
            s.lightmesh.gpu_memory_mib = 0
        }),
        ("default_radius", |s| s.lamps.default_radius = Some(-0.1)),
        ("default_radius", |s| {
            s.lamps.default_radius = Some(f32::NAN)
        }),
        ("`Key`", |s| {
            s.lamps.radius.insert("Key".into(), f32::NAN);
        }),
        ("threads", |s| s.threads = Some(0)),
        ("sheet_thumb_width", |s| s.sheet_thumb_width = Some(0)),
        ("sheet_thumb_width", |s| s.sheet_thumb_width = Some(40000)),
        ("skip_existing", |s| {
            *s = Settings {
                skip_existing: true,
                contact_sheet: Some("sheet.png".into()),
                ..s.clone().preview()
            }
        }),
    ];
    for (field, break_it) in cases {
        let mut settings = Settings::default();
        break_it(&mut settings);
        let message = settings.validate().unwrap_err().to_string();
        assert!(message.contains(field), "{field}: {message}");
    }
    // The limits themselves are fine.
    let mut edge = Settings {
        width: 32768,
        height: 1,
        max_depth: 64,
        ..Settings::default()
    };
    edge.lamps.default_radius = Some(0.0);
    edge.validate().unwrap();
}

#[test]
fn exposure_is_read_and_impossible_exposures_are_rejected() {
    let settings = parse("(png: true, exposure: -1.5)").unwrap();
    assert_eq!(settings.exposure, -1.5);
    settings.validate().unwrap();
    for exposure in [f32::NAN, f32::INFINITY, 65.0, -65.0] {
        let settings = Settings {
            exposure,
            ..Settings::default()
        };
        let message = settings.validate().unwrap_err().to_string();
        assert!(message.contains("exposure"), "{exposure}: {message}");
    }
}
