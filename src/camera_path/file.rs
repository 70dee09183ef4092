//! The camera-path file as a user writes it (RON, README "Camera paths"),
//! and the checks that turn it into waypoints the spline can take: at
//! least two, every number finite, each with one direction, and times that
//! increase once the untimed waypoints are spread over the path.

use glam::DVec3;
use serde::Deserialize;

use super::spline::Ease;

/// The vertical field of view a path has when it names none, in degrees:
/// a normal lens (about 43 mm on a full-frame camera).
pub const DEFAULT_FOV: f64 = 45.0;

/// A camera-path file. (The serde names are those a user's error
/// messages show.)
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "path")]
pub struct PathFile {
    pub waypoints: Vec<WaypointFile>,
    /// Seconds from the first waypoint to the last, when the last has no
    /// time of its own.
    #[serde(default)]
    pub duration: Option<f64>,
    /// Vertical field of view in degrees, where a waypoint names none.
    #[serde(default = "default_fov")]
    pub fov: f64,
    #[serde(default)]
    pub ease: Ease,
    /// Play the path at constant speed (by arc length) instead of at the
    /// waypoints' times.
    #[serde(default)]
    pub constant_speed: bool,
}

fn default_fov() -> f64 {
    DEFAULT_FOV
}

/// One waypoint: where the camera is and where it looks, either at a
/// point or by yaw and pitch.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, rename = "waypoint")]
pub struct WaypointFile {
    pub position: [f64; 3],
    #[serde(default)]
    pub look_at: Option<[f64; 3]>,
    /// Degrees about +Y from looking down −Z (towards −X is positive).
    #[serde(default)]
    pub yaw: Option<f64>,
    /// Degrees above the horizon, −90 to 90.
    #[serde(default)]
    pub pitch: Option<f64>,
    /// Seconds.
    #[serde(default)]
    pub time: Option<f64>,
    /// Vertical field of view in degrees.
    #[serde(default)]
    pub fov: Option<f64>,
}

/// A checked waypoint in the spline's terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Waypoint {
    pub position: DVec3,
    /// Yaw and pitch (radians, yaw continuous along the path) and the
    /// vertical field of view (radians).
    pub aim: DVec3,
    pub time: f64,
}

/// Parses RON text. Optional fields may be written bare (`time: 2.0`) or
/// as `Some(2.0)`.
pub fn parse(text: &str) -> Result<PathFile, String> {
    let options =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    options.from_str(text).map_err(|error| {
        let at = error.position;
        format!("line {}, column {}: {}", at.line, at.col, error.code)
    })
}

impl PathFile {
    /// The waypoints with their directions and times, or the first fault.
    pub fn check(&self) -> Result<Vec<Waypoint>, String> {
        let count = self.waypoints.len();
        if count < 2 {
            return Err(format!(
                "a path needs at least two waypoints; it has {count}"
            ));
        }
        check_fov("fov", self.fov)?;
        if let Some(duration) = self.duration {
            if !(duration.is_finite() && duration > 0.0) {
                return Err(format!(
                    "duration is {duration}; it must be a positive number of seconds"
                ));
            }
        }
        let mut waypoints = Vec::with_capacity(count);
        let mut previous_yaw = None;
        for (index, waypoint) in self.waypoints.iter().enumerate() {
            let fault = |fault: String| format!("waypoints[{index}]: {fault}");
            let (position, aim) = waypoint.aim(self.fov, previous_yaw).map_err(fault)?;
            previous_yaw = Some(aim.x);
            waypoints.push(Waypoint {
                position,
                aim,
                time: 0.0,
            });
        }
        let times = self.times(&waypoints)?;
        for (waypoint, time) in waypoints.iter_mut().zip(times) {
            waypoint.time = time;
        }
        Ok(waypoints)
    }

    /// Each waypoint's time: its own; else 0 for the first and the first's
    /// plus `duration` for the last; else spread between the timed
    /// waypoints around it by distance along the polyline, so the camera
    /// keeps roughly one speed. The result must increase.
    fn times(&self, waypoints: &[Waypoint]) -> Result<Vec<f64>, String> {
        let mut times: Vec<Option<f64>> = self.waypoints.iter().map(|w| w.time).collect();
        for (index, time) in times.iter().enumerate() {
            if let Some(time) = time.filter(|time| !time.is_finite()) {
                return Err(format!(
                    "waypoints[{index}]: time is {time}; it must be finite"
                ));
            }
        }
        let first = *times[0].get_or_insert(0.0);
        let last = times.len() - 1;
        match (times[last], self.duration) {
            (None, Some(duration)) => times[last] = Some(first + duration),
            (None, None) => {
                return Err("the last waypoint has no time and the path no duration".into())
            }
            (Some(time), Some(duration)) if (time - first - duration).abs() > 1e-9 => {
                return Err(format!(
                    "duration is {duration} s, but the waypoints span {} s",
                    time - first
                ))
            }
            (Some(_), _) => {}
        }
        let distance = |from: usize, to: usize| -> f64 {
            (from..to)
                .map(|i| waypoints[i].position.distance(waypoints[i + 1].position))
                .sum()
        };
        let timed: Vec<usize> = (0..times.len()).filter(|&i| times[i].is_some()).collect();
        let mut resolved: Vec<f64> = times.iter().map(|time| time.unwrap_or(0.0)).collect();
        for pair in timed.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let span = distance(a, b);
            for i in a + 1..b {
                let share = match span > 0.0 {
                    true => distance(a, i) / span,
                    false => (i - a) as f64 / (b - a) as f64,
                };
                resolved[i] = resolved[a] + share * (resolved[b] - resolved[a]);
            }
        }
        for i in 1..resolved.len() {
            if resolved[i] <= resolved[i - 1] {
                return Err(format!(
                    "waypoints[{i}]: time {} s is not after waypoints[{}]'s {} s; times must increase",
                    resolved[i],
                    i - 1,
                    resolved[i - 1]
                ));
            }
        }
        Ok(resolved)
    }
}

impl WaypointFile {
    /// The position, and the yaw, pitch and field of view in radians. A
    /// look-at's yaw is taken within half a turn of `previous_yaw`, so the
    /// camera turns the short way; a yaw given in degrees is kept as
    /// written (720 spins twice).
    fn aim(&self, path_fov: f64, previous_yaw: Option<f64>) -> Result<(DVec3, DVec3), String> {
        let position = finite_point("position", self.position)?;
        let fov = self.fov.unwrap_or(path_fov);
        check_fov("fov", fov)?;
        let (yaw, pitch) = match (self.look_at, self.yaw, self.pitch) {
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                return Err("give look_at or yaw and pitch, not both".into())
            }
            (None, None, _) => return Err("give look_at, or yaw (and pitch)".into()),
            (Some(target), None, None) => {
                let target = finite_point("look_at", target)?;
                let (yaw, pitch) = yaw_pitch(target - position)
                    .ok_or("look_at equals position, so it gives no direction")?;
                let turns = previous_yaw.map_or(0.0, |previous| {
                    ((previous - yaw) / std::f64::consts::TAU).round()
                });
                (yaw + turns * std::f64::consts::TAU, pitch)
            }
            (None, Some(yaw), pitch) => {
                let pitch = pitch.unwrap_or(0.0);
                if !(yaw.is_finite() && pitch.is_finite() && pitch.abs() <= 90.0) {
                    return Err(format!(
                        "yaw {yaw} and pitch {pitch}: they must be finite, pitch within ±90 degrees"
                    ));
                }
                (yaw.to_radians(), pitch.to_radians())
            }
        };
        Ok((position, DVec3::new(yaw, pitch, fov.to_radians())))
    }
}

/// Yaw and pitch (radians) of looking along `direction`, None for a zero
/// direction. Yaw 0 looks down −Z, as a glTF camera does.
pub fn yaw_pitch(direction: DVec3) -> Option<(f64, f64)> {
    if direction == DVec3::ZERO {
        return None;
    }
    let across = direction.x.hypot(direction.z);
    Some((
        f64::atan2(-direction.x, -direction.z),
        f64::atan2(direction.y, across),
    ))
}

fn finite_point(name: &str, point: [f64; 3]) -> Result<DVec3, String> {
    let point = DVec3::from_array(point);
    match point.is_finite() {
        true => Ok(point),
        false => Err(format!("{name} {point} has a number that is not finite")),
    }
}

fn check_fov(name: &str, degrees: f64) -> Result<(), String> {
    match degrees.is_finite() && degrees > 0.0 && degrees < 180.0 {
        true => Ok(()),
        false => Err(format!(
            "{name} is {degrees}; a vertical field of view is between 0 and 180 degrees"
        )),
    }
}
