//! Resolving a glTF `uri` (of a buffer or an image) to bytes: `data:` URIs
//! are decoded in memory, anything without a scheme is a path relative to the
//! glTF file. Other schemes (http, file) are refused: a render must not
//! depend on the network or on absolute paths of another machine.

use std::path::Path;

/// The bytes `uri` names, or a one-line reason why they cannot be had.
pub fn read(uri: &str, base: &Path) -> Result<Vec<u8>, String> {
    if uri.starts_with("data:") {
        // Only data URIs reach the glTF crate's decoder: its relative-path
        // branch unwraps a percent-decoding result and could panic.
        let source = gltf::buffer::Source::Uri(uri);
        return gltf::buffer::Data::from_source(source, None)
            .map(|data| data.0)
            .map_err(|error| format!("bad data URI: {error}"));
    }
    if let Some((scheme, _)) = uri.split_once(':') {
        if !scheme.contains('/') {
            return Err(format!("unsupported URI scheme {scheme:?}"));
        }
    }
    let relative = percent_decode(uri)?;
    let path = base.join(relative);
    std::fs::read(&path).map_err(|error| format!("{}: {error}", path.display()))
}

/// Undoes `%XX` escapes (RFC 3986), the only encoding glTF URIs use.
fn percent_decode(uri: &str) -> Result<String, String> {
    let bytes = uri.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut at = 0;
    while at < bytes.len() {
        let escaped = (bytes[at] == b'%')
            .then(|| bytes.get(at + 1..at + 3))
            .flatten()
            .and_then(|hex| std::str::from_utf8(hex).ok())
            .and_then(|hex| u8::from_str_radix(hex, 16).ok());
        match escaped {
            Some(byte) => {
                decoded.push(byte);
                at += 3;
            }
            None => {
                decoded.push(bytes[at]);
                at += 1;
            }
        }
    }
    String::from_utf8(decoded).map_err(|_| format!("URI {uri:?} decodes to invalid UTF-8"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_escapes_decode_and_stray_percents_stay() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Ok("a b.bin"));
        assert_eq!(percent_decode("100%.bin").as_deref(), Ok("100%.bin"));
        assert!(percent_decode("%FF.bin").is_err());
    }

    #[test]
    fn network_schemes_are_refused() {
        let error = read("https://example.com/a.bin", Path::new(".")).unwrap_err();
        assert!(error.contains("https"), "{error}");
    }
}
