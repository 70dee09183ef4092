//! The file that keeps the driver's compiled pipelines between runs, in
//! lmanim's cache folder: wgpu's pipeline cache data (opaque, the
//! driver's own format) in an envelope of ours that says what it holds.
//!
//! Layout (little-endian):
//!
//! ```text
//! magic "LMANIMPC" · format u32 · checksum u64 (XXH3-64 of the body)
//! body: shaders u64 (what made the pipelines) · names u32 · for each:
//!       length u32 · UTF-8 bytes (the pipelines held) · data length u64
//!       · data
//! ```
//!
//! wgpu checks the data's own header (adapter, driver version) and a
//! driver checks its entries, so a foreign file costs nothing but a
//! compile; the envelope is what lets lmanim say which pipelines a run
//! found cached, and tell a torn or corrupt file (a warning) from one
//! made by other shaders (replaced without a word).

use xxhash_rust::xxh3::xxh3_64;

const MAGIC: &[u8; 8] = b"LMANIMPC";
/// Bumped whenever the envelope's layout changes.
const FORMAT: u32 = 1;

/// What a pipeline cache file holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StoredPipelines {
    /// The hash of the shaders the pipelines were made from
    /// (`pipeline_cache::shader_hash`).
    pub shaders: u64,
    /// The names of the pipelines made into the data.
    pub names: Vec<String>,
    /// wgpu's pipeline cache data.
    pub data: Vec<u8>,
}

/// Why a file's bytes are not a pipeline cache.
#[derive(Debug, PartialEq, Eq, thiserror::Error)]
pub enum Fault {
    #[error("not an lmanim pipeline cache (bad magic)")]
    Magic,
    #[error("written by another version of lmanim's pipeline cache format ({0})")]
    Format(u32),
    #[error("cut short")]
    Truncated,
    #[error("a pipeline name is not UTF-8")]
    Name,
    #[error("the checksum does not match (corrupt)")]
    Checksum,
    #[error("{0} bytes after the data")]
    Trailing(usize),
}

impl StoredPipelines {
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut body = Vec::with_capacity(self.data.len() + 64);
        body.extend_from_slice(&self.shaders.to_le_bytes());
        body.extend_from_slice(&(self.names.len() as u32).to_le_bytes());
        for name in &self.names {
            body.extend_from_slice(&(name.len() as u32).to_le_bytes());
            body.extend_from_slice(name.as_bytes());
        }
        body.extend_from_slice(&(self.data.len() as u64).to_le_bytes());
        body.extend_from_slice(&self.data);
        let mut bytes = Vec::with_capacity(body.len() + 20);
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&FORMAT.to_le_bytes());
        bytes.extend_from_slice(&xxh3_64(&body).to_le_bytes());
        bytes.extend_from_slice(&body);
        bytes
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<StoredPipelines, Fault> {
        let mut reader = Reader(bytes);
        if reader.take(MAGIC.len())? != MAGIC {
            return Err(Fault::Magic);
        }
        let format = reader.u32()?;
        if format != FORMAT {
            return Err(Fault::Format(format));
        }
        let checksum = reader.u64()?;
        if xxh3_64(reader.0) != checksum {
            return Err(Fault::Checksum);
        }
        let shaders = reader.u64()?;
        let count = reader.u32()?;
        let names = (0..count)
            .map(|_| {
                let length = reader.u32()? as usize;
                let name = reader.take(length)?;
                String::from_utf8(name.to_vec()).map_err(|_| Fault::Name)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let length = usize::try_from(reader.u64()?).map_err(|_| Fault::Truncated)?;
        let data = reader.take(length)?;
        if !reader.0.is_empty() {
            return Err(Fault::Trailing(reader.0.len()));
        }
        Ok(StoredPipelines {
            shaders,
            names,
            data: data.to_vec(),
        })
    }
}

/// The bytes not read yet.
struct Reader<'a>(&'a [u8]);

impl<'a> Reader<'a> {
    fn take(&mut self, count: usize) -> Result<&'a [u8], Fault> {
        if self.0.len() < count {
            return Err(Fault::Truncated);
        }
        let (taken, rest) = self.0.split_at(count);
        self.0 = rest;
        Ok(taken)
    }

    fn u32(&mut self) -> Result<u32, Fault> {
        let bytes = self.take(4)?;
        Ok(u32::from_le_bytes(bytes.try_into().expect("four bytes")))
    }

    fn u64(&mut self) -> Result<u64, Fault> {
        let bytes = self.take(8)?;
        Ok(u64::from_le_bytes(bytes.try_into().expect("eight bytes")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stored() -> StoredPipelines {
        StoredPipelines {
            shaders: 0x0123_4567_89ab_cdef,
            names: vec!["camera_rays".into(), "light_mesh".into()],
            data: (0..=255u8).cycle().take(1000).collect(),
        }
    }

    #[test]
    fn a_file_reads_back_as_written() {
        let stored = stored();
        assert_eq!(StoredPipelines::from_bytes(&stored.to_bytes()), Ok(stored));
        let empty = StoredPipelines {
            shaders: 0,
            names: Vec::new(),
            data: Vec::new(),
        };
        assert_eq!(StoredPipelines::from_bytes(&empty.to_bytes()), Ok(empty));
    }

    /// Every cut, every flipped byte and every byte added is refused:
    /// no torn or damaged file reaches the driver.
    #[test]
    fn every_damaged_file_is_refused() {
        let bytes = stored().to_bytes();
        for length in 0..bytes.len() {
            assert!(
                StoredPipelines::from_bytes(&bytes[..length]).is_err(),
                "{length}"
            );
        }
        for at in 0..bytes.len() {
            let mut flipped = bytes.clone();
            flipped[at] ^= 0x10;
            assert!(StoredPipelines::from_bytes(&flipped).is_err(), "{at}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert_eq!(StoredPipelines::from_bytes(&longer), Err(Fault::Checksum));
        assert_eq!(
            StoredPipelines::from_bytes(b"GARBAGE!and more"),
            Err(Fault::Magic)
        );
    }
}
