//! glTF cameras, perspective and orthographic.

use super::error::Fault;
use crate::scene::{Camera, Projection};

/// Every camera of the file, in the file's order.
pub fn import(document: &gltf::Document) -> Result<Vec<Camera>, Fault> {
    document
        .cameras()
        .map(|camera| import_one(&camera))
        .collect()
}

fn import_one(camera: &gltf::Camera) -> Result<Camera, Fault> {
    let projection = match camera.projection() {
        gltf::camera::Projection::Perspective(p) => Projection::Perspective {
            yfov: p.yfov(),
            aspect_ratio: p.aspect_ratio(),
            znear: p.znear(),
            zfar: p.zfar(),
        },
        gltf::camera::Projection::Orthographic(o) => Projection::Orthographic {
            xmag: o.xmag(),
            ymag: o.ymag(),
            znear: o.znear(),
            zfar: o.zfar(),
        },
    };
    if let Some(problem) = problem(&projection) {
        return Err(Fault::Camera {
            camera: camera.index(),
            problem: problem.to_owned(),
        });
    }
    Ok(Camera {
        name: camera.name().map(str::to_owned),
        projection,
    })
}

/// What makes a projection unusable for rendering, if anything.
fn problem(projection: &Projection) -> Option<&'static str> {
    let positive = |value: f32| value.is_finite() && value > 0.0;
    match *projection {
        Projection::Perspective {
            yfov,
            aspect_ratio,
            znear,
            zfar,
        } => {
            if !(positive(yfov) && yfov < std::f32::consts::PI) {
                Some("yfov is not within 0..π")
            } else if !aspect_ratio.is_none_or(positive) {
                Some("aspectRatio is not positive")
            } else if !positive(znear) {
                Some("znear is not positive")
            } else if !zfar.is_none_or(|zfar| zfar.is_finite() && zfar > znear) {
                Some("zfar is not beyond znear")
            } else {
                None
            }
        }
        Projection::Orthographic {
            xmag,
            ymag,
            znear,
            zfar,
        } => {
            if !(xmag.is_finite() && ymag.is_finite() && xmag != 0.0 && ymag != 0.0) {
                Some("xmag or ymag is zero or not finite")
            } else if !(znear.is_finite() && znear >= 0.0) {
                Some("znear is negative or not finite")
            } else if !(zfar.is_finite() && zfar > znear) {
                Some("zfar is not beyond znear")
            } else {
                None
            }
        }
    }
}
