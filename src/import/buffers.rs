//! The bytes of every glTF buffer, checked against the sizes the file
//! declares: a buffer's data must hold its `byteLength`, and every buffer
//! view must lie inside its buffer. After this, accessor checks only need to
//! compare against their view.

use std::path::Path;

use super::error::Fault;
use super::uri;

/// Loads each buffer of `document` in order; `bin` is the .glb BIN chunk.
pub fn load(
    document: &gltf::Document,
    bin: Option<&[u8]>,
    base: &Path,
) -> Result<Vec<Vec<u8>>, Fault> {
    let buffers = document
        .buffers()
        .map(|buffer| load_one(&buffer, bin, base))
        .collect::<Result<Vec<_>, _>>()?;
    check_views(document)?;
    Ok(buffers)
}

fn load_one(buffer: &gltf::Buffer, bin: Option<&[u8]>, base: &Path) -> Result<Vec<u8>, Fault> {
    let data = match buffer.source() {
        gltf::buffer::Source::Bin => bin.map(<[u8]>::to_vec).ok_or(Fault::BufferSource {
            buffer: buffer.index(),
            uri: "GLB BIN chunk".to_owned(),
            reason: "the file has no BIN chunk".to_owned(),
        })?,
        gltf::buffer::Source::Uri(text) => {
            uri::read(text, base, uri::Resource::Buffer).map_err(|reason| Fault::BufferSource {
                buffer: buffer.index(),
                uri: shorten(text),
                reason,
            })?
        }
    };
    if data.len() < buffer.length() {
        return Err(Fault::BufferLength {
            buffer: buffer.index(),
            declared: buffer.length(),
            actual: data.len(),
        });
    }
    Ok(data)
}

/// Data URIs can be megabytes long; an error message shows their start.
fn shorten(uri: &str) -> String {
    const SHOWN: usize = 40;
    match uri.char_indices().nth(SHOWN) {
        Some((cut, _)) => format!("{}…", &uri[..cut]),
        None => uri.to_owned(),
    }
}

fn check_views(document: &gltf::Document) -> Result<(), Fault> {
    for view in document.views() {
        let buffer = view.buffer();
        let end = view.offset().checked_add(view.length());
        if end.is_none_or(|end| end > buffer.length()) {
            return Err(Fault::ViewOutOfBounds {
                view: view.index(),
                start: view.offset(),
                end: end.unwrap_or(usize::MAX),
                buffer: buffer.index(),
                length: buffer.length(),
            });
        }
    }
    Ok(())
}
