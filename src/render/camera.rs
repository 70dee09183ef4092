//! The render camera: a glTF camera placed in render space, and the primary
//! ray through any point of the image plane. Stage 1 of a frame asks it for
//! one ray per pixel sample.

use glam::{Vec2, Vec3};

use crate::accel::Ray;
use crate::scene::Projection;

/// A camera in render space with an orthonormal basis; it looks down
/// `-backward`, like a glTF camera looks down its node's −Z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderCamera {
    pub origin: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub backward: Vec3,
    pub projection: Projection,
}

impl RenderCamera {
    /// The primary rays of a `width × height` image: what every ray of the
    /// image shares (its aspect, the tangent of half the field of view)
    /// worked out once, since a frame asks for one ray per pixel sample.
    ///
    /// The vertical field of view (or `ymag`) is kept and the horizontal one
    /// follows the image's aspect, so changing `--width` widens the view
    /// rather than distorting it, as glTF viewers do.
    pub fn film(&self, width: u32, height: u32) -> FilmRays {
        let lens = match self.projection {
            Projection::Perspective { yfov, zfar, .. } => Lens::Perspective {
                tan_half: (0.5 * yfov).tan(),
                zfar: zfar.unwrap_or(f32::INFINITY),
            },
            Projection::Orthographic { ymag, zfar, .. } => Lens::Orthographic { ymag, zfar },
        };
        FilmRays {
            camera: *self,
            width: width as f32,
            height: height as f32,
            aspect: width as f32 / height as f32,
            lens,
        }
    }
}

/// The rays through the points of one image ([`RenderCamera::film`]).
#[derive(Clone, Copy, Debug)]
pub struct FilmRays {
    camera: RenderCamera,
    width: f32,
    height: f32,
    aspect: f32,
    lens: Lens,
}

/// A projection's terms, as its rays use them.
#[derive(Clone, Copy, Debug)]
enum Lens {
    Perspective { tan_half: f32, zfar: f32 },
    Orthographic { ymag: f32, zfar: f32 },
}

impl FilmRays {
    /// The ray through image-plane point `film`, in pixels from the top-left
    /// corner (pixel centres at +0.5).
    pub fn through(&self, film: Vec2) -> Ray {
        let camera = &self.camera;
        let ndc_x = 2.0 * film.x / self.width - 1.0;
        let ndc_y = 1.0 - 2.0 * film.y / self.height;
        let forward = -camera.backward;
        match self.lens {
            Lens::Perspective { tan_half, zfar } => {
                let direction = forward
                    + camera.right * (ndc_x * tan_half * self.aspect)
                    + camera.up * (ndc_y * tan_half);
                // The far plane bounds depth along the view axis; the
                // direction's forward component is exactly 1.
                Ray::new(camera.origin, direction, zfar)
            }
            Lens::Orthographic { ymag, zfar } => {
                let origin = camera.origin
                    + camera.right * (ndc_x * ymag * self.aspect)
                    + camera.up * (ndc_y * ymag);
                Ray::new(origin, forward, zfar)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(projection: Projection) -> RenderCamera {
        RenderCamera {
            origin: Vec3::new(0.0, 1.0, 5.0),
            right: Vec3::X,
            up: Vec3::Y,
            backward: Vec3::Z,
            projection,
        }
    }

    #[test]
    fn centre_ray_looks_down_minus_z_and_corners_span_the_field_of_view() {
        let yfov = 60f32.to_radians();
        let cam = camera(Projection::Perspective {
            yfov,
            aspect_ratio: None,
            znear: 0.1,
            zfar: None,
        });
        let centre = cam.film(100, 50).through(Vec2::new(50.0, 25.0));
        assert_eq!(centre.direction, Vec3::NEG_Z);
        let top = cam.film(100, 50).through(Vec2::new(50.0, 0.0));
        let angle = top.direction.angle_between(Vec3::NEG_Z);
        assert!((angle - 0.5 * yfov).abs() < 1e-6, "{angle}");
        assert!(top.direction.y > 0.0, "top of the image is +Y");
        let right = cam.film(100, 50).through(Vec2::new(100.0, 25.0));
        assert!((right.direction.x - 2.0 * (0.5 * yfov).tan()).abs() < 1e-6);
    }

    #[test]
    fn orthographic_rays_are_parallel_and_offset_by_magnification() {
        let cam = camera(Projection::Orthographic {
            xmag: 2.0,
            ymag: 1.0,
            znear: 0.0,
            zfar: 100.0,
        });
        let corner = cam.film(200, 100).through(Vec2::new(0.0, 0.0));
        assert_eq!(corner.direction, Vec3::NEG_Z);
        assert_eq!(corner.origin, Vec3::new(-2.0, 2.0, 5.0));
        assert_eq!(corner.t_max, 100.0);
    }
}
