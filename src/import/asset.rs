//! The version rules of a file's `asset` object, checked on the raw JSON
//! before anything else reads it: a glTF 1.0 file has another shape
//! altogether, and would otherwise be refused with whatever schema error
//! came first instead of its version.
//!
//! glTF 2.0 §3.2: `asset.version` is `<major>.<minor>`; a reader loads any
//! 2.x asset (later minor versions only add), unless `asset.minVersion`
//! says that the asset needs a newer reader than 2.0, which lmanim is.
//! `minVersion` may not exceed `version`.

use serde_json::Value;

use super::error::Fault;

/// The glTF version lmanim reads.
const READER: Version = Version { major: 2, minor: 0 };

/// Checks `asset.version` and `asset.minVersion` of the raw document.
pub fn check(document: &Value) -> Result<(), Fault> {
    let asset = document.get("asset").ok_or_else(|| {
        rule(
            "asset",
            "is missing; every glTF file states its version there",
        )
    })?;
    let version = asset
        .get("version")
        .ok_or_else(|| rule("asset.version", "is missing; glTF 2.0 requires it"))
        .and_then(|text| Version::parse("asset.version", text))?;
    if version.major != READER.major {
        return Err(rule(
            "asset.version",
            &format!("is {version}: lmanim reads glTF 2.x files, and a major version other than 2 is another format"),
        ));
    }
    let Some(text) = asset.get("minVersion") else {
        return Ok(());
    };
    let min_version = Version::parse("asset.minVersion", text)?;
    if min_version > version {
        return Err(rule(
            "asset.minVersion",
            &format!("is {min_version}, later than asset.version {version}; it may not be"),
        ));
    }
    if min_version > READER {
        return Err(rule(
            "asset.minVersion",
            &format!("is {min_version}: the file needs a glTF {min_version} reader, and lmanim reads glTF {READER}"),
        ));
    }
    Ok(())
}

fn rule(path: &str, rule: &str) -> Fault {
    Fault::Rule {
        path: path.to_owned(),
        rule: rule.to_owned(),
    }
}

/// A glTF version; ordered as versions are (major first).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Version {
    major: u32,
    minor: u32,
}

impl Version {
    /// Parses `<major>.<minor>` (decimal digits only, as the schema's
    /// pattern `^[0-9]+\.[0-9]+$` has it).
    fn parse(path: &str, value: &Value) -> Result<Version, Fault> {
        let malformed = || {
            rule(
                path,
                &format!("is {value}, not a version of the form \"2.0\""),
            )
        };
        let text = value.as_str().ok_or_else(malformed)?;
        let (major, minor) = text.split_once('.').ok_or_else(malformed)?;
        let number = |digits: &str| {
            let decimal = !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit());
            decimal.then(|| digits.parse::<u32>().ok()).flatten()
        };
        match (number(major), number(minor)) {
            (Some(major), Some(minor)) => Ok(Version { major, minor }),
            _ => Err(malformed()),
        }
    }
}

impl std::fmt::Display for Version {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "\"{}.{}\"", self.major, self.minor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn outcome(asset: Value) -> Result<(), String> {
        check(&json!({ "asset": asset })).map_err(|fault| fault.to_string())
    }

    #[test]
    fn every_2_x_version_is_read_unless_it_needs_a_later_reader() {
        for asset in [
            json!({ "version": "2.0" }),
            json!({ "version": "2.1" }),
            json!({ "version": "2.10", "minVersion": "2.0" }),
        ] {
            assert_eq!(outcome(asset.clone()), Ok(()), "{asset}");
        }
    }

    #[test]
    fn other_versions_are_refused_with_the_path_and_the_rule() {
        let cases = [
            (
                json!({ "version": "1.0" }),
                "asset.version: is \"1.0\": lmanim reads glTF 2.x",
            ),
            (json!({ "version": "3.0" }), "asset.version: is \"3.0\""),
            (json!({ "version": "2" }), "not a version of the form"),
            (json!({ "version": "2.0.1" }), "not a version of the form"),
            (json!({ "version": " 2.0" }), "not a version of the form"),
            (
                json!({ "version": 2.0 }),
                "asset.version: is 2.0, not a version",
            ),
            (json!({}), "asset.version: is missing"),
            (
                json!({ "version": "2.1", "minVersion": "2.1" }),
                "asset.minVersion: is \"2.1\": the file needs a glTF \"2.1\" reader",
            ),
            (
                json!({ "version": "2.0", "minVersion": "2.1" }),
                "later than asset.version",
            ),
        ];
        for (asset, words) in cases {
            let message = outcome(asset.clone()).expect_err(words);
            assert!(message.contains(words), "{asset}: {message}");
        }
        let message = check(&json!({})).expect_err("no asset").to_string();
        assert!(message.starts_with("asset: is missing"), "{message}");
    }
}
