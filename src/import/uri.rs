//! Resolving a glTF `uri` (of a buffer or an image) to bytes: `data:` URIs
//! are decoded in memory, anything without a scheme is a path relative to the
//! glTF file. Other schemes (http, file) are refused: a render must not
//! depend on the network or on absolute paths of another machine.
//!
//! A data URI must be base64 and of a media type the spec allows for what
//! it holds (glTF 2.0 §3.6.1.1 and §3.8.2.1): a `text/plain` buffer is not
//! binary data, whatever its bytes decode to.

use std::path::Path;

/// What a URI holds, which decides the media types its data URI may have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resource {
    Buffer,
    Image,
}

impl Resource {
    fn media_types(self) -> &'static [&'static str] {
        match self {
            Resource::Buffer => &["application/octet-stream", "application/gltf-buffer"],
            Resource::Image => &["image/png", "image/jpeg"],
        }
    }
}

/// The bytes `uri` names, or a one-line reason why they cannot be had.
pub fn read(uri: &str, base: &Path, resource: Resource) -> Result<Vec<u8>, String> {
    if let Some(header) = uri.strip_prefix("data:") {
        check_data_header(header, resource)?;
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

/// Checks the part of a data URI before its comma: `<media type>[;<param>]*;base64`.
/// An empty media type is `text/plain` (RFC 2397).
fn check_data_header(after_scheme: &str, resource: Resource) -> Result<(), String> {
    let header = after_scheme
        .split_once(',')
        .map_or(after_scheme, |(header, _)| header);
    let mut parts = header.split(';');
    let media_type = parts.next().unwrap_or_default();
    let allowed = resource.media_types();
    if !allowed
        .iter()
        .any(|allowed| allowed.eq_ignore_ascii_case(media_type))
    {
        let media_type = if media_type.is_empty() {
            "text/plain"
        } else {
            media_type
        };
        return Err(format!(
            "its data URI has media type {media_type:?}; glTF allows only {} for {}",
            allowed.join(" or "),
            match resource {
                Resource::Buffer => "a buffer",
                Resource::Image => "an image",
            }
        ));
    }
    if parts.next_back() != Some("base64") {
        return Err("its data URI is not base64; glTF data URIs must be".to_owned());
    }
    Ok(())
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
        let error = read(
            "https://example.com/a.bin",
            Path::new("."),
            Resource::Buffer,
        )
        .unwrap_err();
        assert!(error.contains("https"), "{error}");
    }

    #[test]
    fn data_uris_need_their_resource_s_media_type_and_base64() {
        let read = |uri: &str, resource| read(uri, Path::new("."), resource);
        assert_eq!(
            read(
                "data:application/gltf-buffer;base64,AAECAw==",
                Resource::Buffer
            ),
            Ok(vec![0, 1, 2, 3])
        );
        let cases = [
            (
                "data:text/plain;base64,AAAA",
                Resource::Buffer,
                "media type \"text/plain\"",
            ),
            (
                "data:;base64,AAAA",
                Resource::Buffer,
                "media type \"text/plain\"",
            ),
            (
                "data:image/png;base64,AAAA",
                Resource::Buffer,
                "application/octet-stream or",
            ),
            (
                "data:application/octet-stream;base64,AAAA",
                Resource::Image,
                "image/png or image/jpeg",
            ),
            (
                "data:application/octet-stream,%00%01",
                Resource::Buffer,
                "not base64",
            ),
        ];
        for (uri, resource, words) in cases {
            let reason = read(uri, resource).expect_err(uri);
            assert!(reason.contains(words), "{uri}: {reason}");
        }
    }
}
