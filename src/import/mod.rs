//! STUB: glTF 2.0 (.gltf, .glb) → [`SceneDesc`].

use std::path::Path;

use crate::scene::SceneDesc;

#[derive(Debug, thiserror::Error)]
#[error("{file}: {fault}")]
pub struct ImportError {
    pub file: String,
    pub fault: String,
}

pub fn load(_path: &Path) -> Result<SceneDesc, ImportError> {
    todo!()
}
