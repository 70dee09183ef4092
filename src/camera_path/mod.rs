//! Camera paths: a fly-through written as a few waypoints in a RON file
//! (`--camera-path`, [`file`]) or made by the turntable preset
//! (`--orbit`), flown instead of the scene's cameras. The frame loop and
//! the effect plan ask [`CameraPath::pose_at`] for each frame's camera at
//! time f / fps (through `CameraChoice::for_frame`), so a path is just
//! another camera to them: moving it changes no geometry and invalidates
//! no light-mesh bit. [`bake`] writes the same poses into a glTF camera
//! node and clip, so other players show the same shot.
//!
//! Positions follow a centripetal Catmull–Rom spline ([`spline`]); the
//! view's yaw, pitch and field of view follow the same parameterisation,
//! so the camera turns while it moves rather than at the waypoints, and
//! never looks through a degenerate direction between them.

pub mod bake;
pub mod file;
pub mod spline;

use std::path::Path;

use glam::{DMat4, DQuat, DVec3};

use crate::scene::Projection;
use file::{PathFile, Waypoint, WaypointFile};
use spline::{ArcTable, Ease, Spline};

/// The near plane of a path's camera, in metres (glTF requires one; the
/// renderer's rays start at the eye).
pub const ZNEAR: f32 = 0.1;

/// Waypoints of the `--orbit` turntable: one every 15 degrees, on a
/// closed spline, keeps the camera within 1e-3 of the circle's radius
/// (tested).
const ORBIT_STEPS: usize = 24;

/// A path's fault: the file (or flag) it came from and what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{origin}: {fault}")]
pub struct PathError {
    pub origin: String,
    pub fault: String,
}

/// A checked camera path, ready to be sampled at any time.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    times: Vec<f64>,
    spline: Spline,
    ease: Ease,
    /// Present when the path plays at constant speed.
    arc: Option<ArcTable>,
}

/// Where the path's camera is at one time, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPose {
    pub position: DVec3,
    /// Turns the camera's −Z onto its view direction, with no roll.
    pub rotation: DQuat,
    /// Vertical field of view in radians.
    pub yfov: f64,
}

impl CameraPose {
    /// The camera node's world transform.
    pub fn world(&self) -> DMat4 {
        DMat4::from_rotation_translation(self.rotation, self.position)
    }

    /// A perspective projection that keeps the output image's aspect.
    pub fn projection(&self) -> Projection {
        Projection::Perspective {
            yfov: self.yfov as f32,
            aspect_ratio: None,
            znear: ZNEAR,
            zfar: None,
        }
    }
}

impl CameraPath {
    /// Reads and checks a camera-path file; errors name the file.
    pub fn load(path: &Path) -> Result<CameraPath, PathError> {
        let origin = path.display().to_string();
        let fault = |fault| PathError {
            origin: origin.clone(),
            fault,
        };
        let text = std::fs::read_to_string(path).map_err(|error| fault(error.to_string()))?;
        let file = file::parse(&text).map_err(fault)?;
        CameraPath::new(&file).map_err(fault)
    }

    /// The turntable `--orbit X,Y,Z,RADIUS,HEIGHT,SECONDS`: one turn around
    /// the target (X, Y, Z) at RADIUS metres, HEIGHT metres above it,
    /// looking at it, at constant speed, in SECONDS; it starts on the
    /// target's +Z side and heads towards +X.
    pub fn orbit(text: &str) -> Result<CameraPath, PathError> {
        let fault = |fault: String| PathError {
            origin: format!("--orbit {text}"),
            fault,
        };
        let numbers = text
            .split(',')
            .map(|item| item.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
            .collect::<Option<Vec<f64>>>();
        let Some(&[x, y, z, radius, height, seconds]) = numbers.as_deref() else {
            return Err(fault(
                "expected six finite numbers X,Y,Z,RADIUS,HEIGHT,SECONDS".into(),
            ));
        };
        if radius <= 0.0 || seconds <= 0.0 {
            return Err(fault("RADIUS and SECONDS must be above 0".into()));
        }
        let target = DVec3::new(x, y, z);
        let waypoints = (0..=ORBIT_STEPS)
            .map(|step| {
                // The last waypoint is the first, exactly: a closed loop.
                let step = step % ORBIT_STEPS;
                let angle = std::f64::consts::TAU * step as f64 / ORBIT_STEPS as f64;
                let offset = DVec3::new(radius * angle.sin(), height, radius * angle.cos());
                WaypointFile {
                    position: (target + offset).to_array(),
                    look_at: Some(target.to_array()),
                    ..WaypointFile::default()
                }
            })
            .collect();
        let file = PathFile {
            waypoints,
            duration: Some(seconds),
            fov: file::DEFAULT_FOV,
            ease: Ease::Linear,
            constant_speed: true,
        };
        CameraPath::new(&file).map_err(fault)
    }

    fn new(file: &PathFile) -> Result<CameraPath, String> {
        let waypoints = file.check()?;
        let points: Vec<DVec3> = waypoints.iter().map(|w| w.position).collect();
        let aims: Vec<DVec3> = waypoints.iter().map(|w| w.aim).collect();
        let spline = Spline::new(&points, &aims);
        Ok(CameraPath {
            times: waypoints.iter().map(|w: &Waypoint| w.time).collect(),
            arc: file.constant_speed.then(|| spline.arc_table()),
            spline,
            ease: file.ease,
        })
    }

    /// The first waypoint's time: before it the camera waits there.
    pub fn start(&self) -> f64 {
        self.times[0]
    }

    /// The last waypoint's time: after it the camera stays there.
    pub fn end(&self) -> f64 {
        self.times[self.times.len() - 1]
    }

    /// The camera at `time` seconds. The ease warps the path's clock
    /// between its first and last times; at constant speed the eased share
    /// of the time is that share of the path's length, and the waypoints
    /// in between are passed where the length puts them.
    pub fn pose_at(&self, time: f64) -> CameraPose {
        let (start, end) = (self.start(), self.end());
        let share = self.ease.apply((time - start) / (end - start));
        let (segment, s) = match &self.arc {
            Some(arc) if arc.total() > 0.0 => arc.segment_at(share * arc.total()),
            _ => self.segment_at_clock(start + share * (end - start)),
        };
        let (position, aim) = self.spline.at(segment, s);
        CameraPose {
            position,
            rotation: DQuat::from_rotation_y(aim.x) * DQuat::from_rotation_x(aim.y),
            yfov: aim.z.clamp(1e-3, std::f64::consts::PI - 1e-3),
        }
    }

    /// The segment and its share at `clock` seconds of the waypoints' times.
    fn segment_at_clock(&self, clock: f64) -> (usize, f64) {
        let last = self.times.len() - 2;
        let segment = self
            .times
            .partition_point(|&t| t <= clock)
            .clamp(1, last + 1)
            - 1;
        let (t0, t1) = (self.times[segment], self.times[segment + 1]);
        (segment, ((clock - t0) / (t1 - t0)).clamp(0.0, 1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path(text: &str) -> Result<CameraPath, String> {
        CameraPath::new(&file::parse(text)?)
    }

    const FLIGHT: &str = "(
        fov: 50,
        waypoints: [
            (position: (0, 10, 40), look_at: (0, 0, 0)),
            (position: (20, 12, 20), look_at: (0, 0, 0), time: 2.0, fov: 40),
            (position: (30, 8, -10), yaw: 120, pitch: -10),
            (position: (0, 6, -30), look_at: (0, 2, 0), time: 8),
        ],
    )";

    fn direction(pose: &CameraPose) -> DVec3 {
        pose.rotation * DVec3::NEG_Z
    }

    #[test]
    fn the_camera_passes_each_waypoint_at_its_time_looking_its_way() {
        let path = path(FLIGHT).unwrap();
        let start = path.pose_at(0.0);
        assert!(start
            .position
            .abs_diff_eq(DVec3::new(0.0, 10.0, 40.0), 1e-12));
        let towards = (DVec3::ZERO - start.position).normalize();
        assert!(direction(&start).abs_diff_eq(towards, 1e-12));
        assert!((start.yfov - 50f64.to_radians()).abs() < 1e-12);
        let second = path.pose_at(2.0);
        assert!(second
            .position
            .abs_diff_eq(DVec3::new(20.0, 12.0, 20.0), 1e-12));
        assert!((second.yfov - 40f64.to_radians()).abs() < 1e-12);
        let up = second.rotation * DVec3::Y;
        assert!(
            (up.cross(direction(&second))).dot(DVec3::Y).abs() < 1e-12,
            "no roll"
        );
        let after = path.pose_at(100.0);
        assert!(after
            .position
            .abs_diff_eq(DVec3::new(0.0, 6.0, -30.0), 1e-12));
        // The untimed third waypoint is spread by distance between 2 s and 8 s.
        let third = path.times[2];
        assert!(third > 2.0 && third < 8.0, "{third}");
        let yawed = path.pose_at(third);
        let want = DQuat::from_rotation_y(120f64.to_radians())
            * DQuat::from_rotation_x(-10f64.to_radians());
        assert!(direction(&yawed).abs_diff_eq(want * DVec3::NEG_Z, 1e-12));
    }

    #[test]
    fn constant_speed_covers_equal_lengths_in_equal_times() {
        let text = FLIGHT.replace("fov: 50,", "fov: 50, constant_speed: true,");
        let path = path(&text).unwrap();
        let steps = 32;
        let at = |k: usize| path.pose_at(8.0 * k as f64 / steps as f64).position;
        let lengths: Vec<f64> = (0..steps)
            .map(|k| {
                (0..50)
                    .map(|j| {
                        let t = |j: usize| 8.0 * (k as f64 + j as f64 / 50.0) / steps as f64;
                        path.pose_at(t(j))
                            .position
                            .distance(path.pose_at(t(j + 1)).position)
                    })
                    .sum()
            })
            .collect();
        let mean = lengths.iter().sum::<f64>() / steps as f64;
        for (k, length) in lengths.iter().enumerate() {
            assert!(
                (length - mean).abs() < 1e-3 * mean,
                "{k}: {length} vs {mean}"
            );
        }
        assert!(at(steps).abs_diff_eq(DVec3::new(0.0, 6.0, -30.0), 1e-9));
    }

    #[test]
    fn an_ease_in_out_starts_and_ends_at_rest() {
        let text = FLIGHT.replace("fov: 50,", "fov: 50, ease: ease_in_out,");
        let path = path(&text).unwrap();
        let step = |t: f64| {
            path.pose_at(t + 1e-4)
                .position
                .distance(path.pose_at(t).position)
        };
        assert!(step(0.0) < 1e-5 && step(8.0 - 1e-4) < 1e-5);
        assert!(step(4.0) > 1e-4);
    }

    #[test]
    fn an_orbit_circles_its_target_looking_at_it() {
        let path = CameraPath::orbit("1,2,3,10,5,12").unwrap();
        let target = DVec3::new(1.0, 2.0, 3.0);
        assert_eq!(path.end(), 12.0);
        for k in 0..=48 {
            let pose = path.pose_at(12.0 * k as f64 / 48.0);
            let offset = pose.position - target;
            let radius = offset.x.hypot(offset.z);
            assert!((radius - 10.0).abs() < 1e-2, "{k}: {radius}");
            assert!((offset.y - 5.0).abs() < 1e-9);
            let towards = -offset.normalize();
            assert!(direction(&pose).angle_between(towards) < 1e-3, "{k}");
        }
        let message = CameraPath::orbit("0,0,0,-1,2,3").unwrap_err().to_string();
        assert!(message.starts_with("--orbit 0,0,0,-1,2,3: "), "{message}");
        assert!(CameraPath::orbit("0,0,0,1,2").is_err());
    }

    #[test]
    fn bad_paths_are_refused_with_their_fault() {
        let cases = [
            ("(waypoints: [(position: (0,0,0), yaw: 0)], duration: 2)", "at least two"),
            (
                "(waypoints: [(position: (0,0,0), yaw: 0, time: 2), (position: (1,0,0), yaw: 0, time: 1)])",
                "times must increase",
            ),
            (
                "(waypoints: [(position: (0,0,0), look_at: (0,0,0)), (position: (1,0,0), yaw: 0)], duration: 1)",
                "look_at equals position",
            ),
            (
                "(waypoints: [(position: (0,inf,0), yaw: 0), (position: (1,0,0), yaw: 0)], duration: 1)",
                "not finite",
            ),
            (
                "(waypoints: [(position: (0,0,0), yaw: 0), (position: (1,0,0), yaw: 0)], duration: NaN)",
                "duration",
            ),
            (
                "(waypoints: [(position: (0,0,0), yaw: 0, roll: 3), (position: (1,0,0), yaw: 0)], duration: 1)",
                "roll",
            ),
            (
                "(waypoints: [(position: (0,0,0), yaw: 0), (position: (1,0,0), yaw: 0)])",
                "no duration",
            ),
            (
                "(waypoints: [(position: (0,0,0)), (position: (1,0,0), yaw: 0)], duration: 1)",
                "give look_at",
            ),
        ];
        for (text, needle) in cases {
            let fault = path(text).unwrap_err();
            assert!(fault.contains(needle), "{text}: {fault}");
        }
    }

    #[test]
    fn a_two_point_path_and_a_hold_give_finite_poses() {
        let two = path("(waypoints: [(position: (0,0,0), yaw: 0), (position: (0,0,0), yaw: 90)], duration: 1, constant_speed: true)").unwrap();
        for k in 0..=10 {
            let pose = two.pose_at(k as f64 / 10.0);
            assert!(pose.position.is_finite() && pose.rotation.is_finite());
        }
        let turned = direction(&two.pose_at(1.0));
        assert!(turned.abs_diff_eq(DVec3::NEG_X, 1e-12), "{turned}");
    }
}
