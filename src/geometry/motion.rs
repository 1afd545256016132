//! Rigid paths of instances over the frames of an animation: the papers' premise, "dynamic
//! scenes composed of rigid, non-penetrating objects" (Gaitatzes et al. 2008 and 2010,
//! abstracts), in a spec's terms.
//!
//! An instance's [`Motion`] gives, at every frame, a [`Pose`] relative to its placement: a
//! rotation about the centre c of its placed bounding sphere and a displacement of that centre,
//! x ↦ c + d + R·(x − c). Four paths make it, any of them together:
//! - `keyframes` ([`Keyframe`]): a translation and a rotation at given times, the translation
//!   interpolated linearly and the rotation by slerp (the shorter arc between consecutive
//!   keys: a turn of 180° or more is split into keys), held before the first key and after the
//!   last; the rotation turns about `pivot` (default c), so that the same keys and pivot on
//!   every instance move the scene as one rigid body;
//! - `orbit` ([`Orbit`]): c travels a circle about an axis through `center`, one turn per
//!   `period` seconds; with `turn`, the instance turns with it (a turntable);
//! - `tumble` ([`Tumble`]): a turn about c at a constant rate, about a given or seeded axis;
//! - `walk` ([`Walk`]): a seeded random walk of c, one step of `speed` × the time step per
//!   frame, in a seeded direction (in a plane, with `plane_normal`).
//!
//! The rotations compose about c (the tumble first, then the keyframes', then the orbit's
//! turn); the displacements add. Frame `f` is at time `f · dt`. Everything is computed in f64
//! relative to the placement's parts ([`Pose::apply`]), so that a scene translated far from the
//! origin moves as the untranslated one does (see [`super::rebase`]).

use super::rebase::Placement;
use glam::{DQuat, DVec3, EulerRot, Vec3};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// An instance's rigid path: any of keyframes, an orbit, a tumble and a random walk (see the
/// module docs for how they combine).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Motion {
    /// Translations and rotations at given times (strictly increasing).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub keyframes: Vec<Keyframe>,
    /// The point the keyframes' rotations turn about (spec world); default the centre of the
    /// instance's placed bounding sphere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pivot: Option<DVec3>,
    /// A circle about an axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orbit: Option<Orbit>,
    /// A turn about the instance's centre at a constant rate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tumble: Option<Tumble>,
    /// A seeded random walk of the instance's centre.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub walk: Option<Walk>,
}

/// One key of [`Motion::keyframes`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Seconds.
    pub time: f64,
    /// Translation from the placement (spec world units).
    #[serde(default)]
    pub translate: DVec3,
    /// Rotation: degrees about x, y and z composed as R = R_y · R_x · R_z, as a transform's
    /// `rotate_deg`.
    #[serde(default)]
    pub rotate_deg: DVec3,
}

/// [`Motion::orbit`]: the instance's centre c on a circle about the axis through `center`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Orbit {
    /// A point of the axis (spec world); default c itself (then `radius` is needed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<DVec3>,
    /// The axis direction (any length but 0); the turn is right-handed about it.
    pub axis: DVec3,
    /// The circle's radius; default c's distance from the axis. At phase 0, c sits on the
    /// circle in the direction of c from the axis (any direction across the axis when c is on
    /// it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// Seconds per turn (negative: the other way round).
    pub period: f64,
    /// The angle at time 0, degrees.
    #[serde(default)]
    pub phase_deg: f64,
    /// The instance turns with the orbit's angle about the axis (as on a turntable); default it
    /// keeps its orientation.
    #[serde(default)]
    pub turn: bool,
}

/// [`Motion::tumble`]: a turn about the instance's centre.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tumble {
    /// Degrees per second (right-handed about the axis).
    pub rate_deg: f64,
    /// The axis (any length but 0); default one drawn uniformly on the sphere from `seed`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<DVec3>,
    #[serde(default)]
    pub seed: u64,
}

/// [`Motion::walk`]: per frame, the centre steps `speed × dt` in a seeded direction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Walk {
    /// World units per second (at least 0).
    pub speed: f64,
    #[serde(default)]
    pub seed: u64,
    /// Steps lie in the plane across this direction (a walk on a floor); default any
    /// direction, uniform on the sphere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plane_normal: Option<DVec3>,
}

/// Where an instance is at one frame relative to its placement: turned by `rotation` about the
/// centre c of its placed bounding sphere, and c moved by `displacement`:
/// x ↦ c + displacement + rotation · (x − c).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub rotation: DQuat,
    pub displacement: DVec3,
}

impl Pose {
    /// Where the placement puts it.
    pub const IDENTITY: Pose = Pose {
        rotation: DQuat::IDENTITY,
        displacement: DVec3::ZERO,
    };

    /// The placement moved by this pose, for a mesh whose bounding sphere's model-space centre
    /// is `model_centre`: the rotation composed onto the placement's and the centre's
    /// correction, `s·(R₀·m) − s·(R·R₀·m)`, added to its offset; the displacement joins the
    /// large translation where the sum holds it exactly, else the offset. Either way a scene's
    /// coordinates relative to a rebasing origin ([`Placement::relative_to`]) are rounded
    /// once: a scene moved as a whole by a multiple of the rebasing step (by its motions, or by
    /// its placements with its motions' points) keeps its coordinates bit for bit. The
    /// identity returns the placement bit for bit.
    pub fn apply(&self, p: &Placement, model_centre: Vec3) -> Placement {
        if *self == Pose::IDENTITY {
            return *p;
        }
        let d = self.displacement;
        let (translation, d) = if (p.translation + d) - p.translation == d {
            (p.translation + d, DVec3::ZERO)
        } else {
            (p.translation, d)
        };
        if self.rotation == DQuat::IDENTITY {
            return Placement {
                translation,
                offset: p.offset + d,
                ..*p
            };
        }
        let s = p.scale as f64;
        let rotation = (self.rotation.as_quat() * p.rotation).normalize();
        let before = s * (p.rotation * model_centre).as_dvec3();
        let after = s * (rotation * model_centre).as_dvec3();
        Placement {
            rotation,
            translation,
            scale: p.scale,
            offset: p.offset + (d + (before - after)),
        }
    }
}

/// A spec vector as errors show it, each component in Rust's shortest form (`[0.0, 1e300, 0.0]`).
fn show(v: DVec3) -> String {
    format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z)
}

/// A seeded value in [0, 1) of (i, salt), 24 bits (splitmix64's finaliser): the seeded
/// directions of tumbles and walks, and `experiment dynamic`'s phases and axes.
pub fn seeded_unit(i: usize, salt: u64) -> f32 {
    let mut x = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ salt;
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 27;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// A direction uniform on the unit sphere from two seeded values of (i, salt).
fn seeded_direction(i: usize, salt: u64) -> DVec3 {
    let z = 2.0 * seeded_unit(i, salt) as f64 - 1.0;
    let a = TAU * seeded_unit(i, salt ^ 0x5DEE_CE66) as f64;
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(r * a.cos(), z, r * a.sin())
}

/// The rotation of a `rotate_deg` (R = R_y · R_x · R_z).
fn euler(deg: DVec3) -> DQuat {
    DQuat::from_euler(
        EulerRot::YXZ,
        deg.y.to_radians(),
        deg.x.to_radians(),
        deg.z.to_radians(),
    )
}

/// `turns` whole turns removed: the angle in radians of a fraction of a turn, exact for any
/// number of turns within f64.
fn angle_of_turns(turns: f64) -> f64 {
    TAU * turns.rem_euclid(1.0)
}

/// Where `t` lies between key times `a < t < b`, as a fraction in [0, 1]. The span `b − a` of
/// two finite times overflows past f64's range (keys at ±1e308); it is then taken over the
/// halves, which are exact at such magnitudes, so that no finite keys give an infinite span (and
/// a fraction of 0: a key never left).
fn key_fraction(t: f64, a: f64, b: f64) -> f64 {
    let span = b - a;
    if span.is_finite() {
        (t - a) / span
    } else {
        (0.5 * t - 0.5 * a) / (0.5 * b - 0.5 * a)
    }
}

impl Keyframe {
    fn rotation(&self) -> DQuat {
        euler(self.rotate_deg)
    }
}

/// A walk's steps at one time step: step `i` (frames 1, 2, …) is `speed × dt` along a seeded
/// direction, on the sphere or in the plane across `plane_normal`.
struct WalkSteps {
    length: f64,
    seed: u64,
    /// Two unit vectors spanning the plane of the steps (none: any direction).
    plane: Option<(DVec3, DVec3)>,
}

impl WalkSteps {
    fn new(w: &Walk, dt: f64) -> WalkSteps {
        WalkSteps {
            length: w.speed * dt,
            seed: w.seed,
            plane: w.plane_normal.and_then(DVec3::try_normalize).map(|n| {
                let e1 = n.any_orthonormal_vector();
                (e1, n.cross(e1))
            }),
        }
    }

    /// The step into frame `i` (from frame i − 1).
    fn step(&self, i: u32) -> DVec3 {
        let i = i as usize;
        let dir = match self.plane {
            Some((e1, e2)) => {
                let a = TAU * seeded_unit(i, self.seed) as f64;
                a.cos() * e1 + a.sin() * e2
            }
            None => seeded_direction(i, self.seed),
        };
        self.length * dir
    }
}

impl Motion {
    /// Whether it names any path.
    pub fn is_empty(&self) -> bool {
        self.keyframes.is_empty()
            && self.orbit.is_none()
            && self.tumble.is_none()
            && self.walk.is_none()
    }

    /// The keyframes' (rotation, translation) at time `t`.
    fn keyed(&self, t: f64) -> (DQuat, DVec3) {
        let keys = &self.keyframes;
        let (Some(first), Some(last)) = (keys.first(), keys.last()) else {
            return (DQuat::IDENTITY, DVec3::ZERO);
        };
        if t <= first.time {
            return (first.rotation(), first.translate);
        }
        if t >= last.time {
            return (last.rotation(), last.translate);
        }
        let i = keys.partition_point(|k| k.time <= t) - 1;
        let (a, b) = (&keys[i], &keys[i + 1]);
        let u = key_fraction(t, a.time, b.time);
        (
            a.rotation().slerp(b.rotation(), u),
            a.translate.lerp(b.translate, u),
        )
    }

    /// The pose at frame `frame` (time `frame · dt`) of an instance placed by `placement`,
    /// whose mesh's bounding sphere has model-space centre `model_centre`. Every point the
    /// paths name is taken relative to the placed centre c as `(translation − P) + rest`, the
    /// large translation apart, so that a scene translated as a whole (its points with it)
    /// gets the same displacements. A walk's first `frame` steps are summed here: over a run,
    /// [`Self::poses`] steps it once a frame.
    pub fn pose(&self, frame: u32, dt: f64, placement: &Placement, model_centre: Vec3) -> Pose {
        let walked = self.walk.as_ref().map(|w| {
            let steps = WalkSteps::new(w, dt);
            (1..=frame).fold(DVec3::ZERO, |sum, i| sum + steps.step(i))
        });
        self.pose_walked(frame, dt, placement, model_centre, walked)
    }

    /// [`Self::pose`] at frames `0..frames`, the walk's steps summed once over the run (each
    /// frame's sum is the previous one plus one step, as [`Self::pose`] sums them): O(frames)
    /// in all, where a pose per frame costs O(frames²).
    pub fn poses(
        &self,
        frames: u32,
        dt: f64,
        placement: &Placement,
        model_centre: Vec3,
    ) -> Vec<Pose> {
        let steps = self.walk.as_ref().map(|w| WalkSteps::new(w, dt));
        let mut walked = DVec3::ZERO;
        (0..frames)
            .map(|f| {
                let w = steps.as_ref().map(|s| {
                    if f > 0 {
                        walked += s.step(f);
                    }
                    walked
                });
                self.pose_walked(f, dt, placement, model_centre, w)
            })
            .collect()
    }

    /// The pose at frame `frame`, given the sum of its walk's steps to that frame (none: no
    /// walk); the walk's sum is added after the other paths' displacements.
    fn pose_walked(
        &self,
        frame: u32,
        dt: f64,
        placement: &Placement,
        model_centre: Vec3,
        walked: Option<DVec3>,
    ) -> Pose {
        let t = frame as f64 * dt;
        let rest = placement.offset
            + placement.scale as f64 * (placement.rotation * model_centre).as_dvec3();
        // c − P for a point P of the spec world.
        let from = |p: DVec3| (placement.translation - p) + rest;
        let mut rotation = DQuat::IDENTITY;
        let mut displacement = DVec3::ZERO;
        if let Some(tu) = &self.tumble {
            let axis = tu
                .axis
                .and_then(DVec3::try_normalize)
                .unwrap_or_else(|| seeded_direction(0, tu.seed));
            rotation = DQuat::from_axis_angle(axis, angle_of_turns(tu.rate_deg * t / 360.0));
        }
        if !self.keyframes.is_empty() {
            let (r, d) = self.keyed(t);
            // Turned about the pivot: c ↦ P + R·(c − P) + d.
            let v = self.pivot.map_or(DVec3::ZERO, from);
            displacement += d + (r * v - v);
            rotation = r * rotation;
        }
        if let Some(o) = &self.orbit {
            let axis = o.axis.try_normalize().unwrap_or(DVec3::Y);
            let v = o.center.map_or(DVec3::ZERO, from);
            let across = v - v.dot(axis) * axis;
            let radius = o.radius.unwrap_or(across.length());
            let u = across
                .try_normalize()
                .unwrap_or_else(|| axis.any_orthonormal_vector());
            let angle = angle_of_turns(t / o.period) + o.phase_deg.to_radians();
            let turned = DQuat::from_axis_angle(axis, angle);
            displacement += turned * (radius * u) - across;
            if o.turn {
                rotation = turned * rotation;
            }
        }
        if let Some(w) = walked.filter(|_| frame > 0) {
            displacement += w;
        }
        Pose {
            rotation,
            displacement,
        }
    }

    /// A bound on how far the paths move the instance's centre over `frames` frames of `dt`
    /// seconds, from the spec's values alone (before any mesh is loaded): the keyframes'
    /// largest translation, twice the orbit's radius where it is given, the walk's length.
    /// What depends on the placed instance (a turn about a far pivot, an orbit about a far
    /// centre) is bounded frame by frame once the scene is built.
    fn reach(&self, frames: u32, dt: f64) -> f64 {
        let keys = self
            .keyframes
            .iter()
            .map(|k| k.translate.abs().max_element())
            .fold(0.0, f64::max);
        let radius = self.orbit.as_ref().and_then(|o| o.radius).unwrap_or(0.0);
        let walk = self
            .walk
            .as_ref()
            .map_or(0.0, |w| w.speed * dt * frames.saturating_sub(1) as f64);
        keys + 2.0 * radius + walk
    }

    /// What is wrong with this motion over `frames` frames of `dt` seconds, if anything: (its
    /// field below the instance's `motion`, why). Every value must be finite, and so must
    /// what the poses form from it over the animation (an orbit's turns t / period, a
    /// tumble's angle, a walk's step speed · dt); every axis of non-zero length, keyframe
    /// times strictly increasing, a period non-zero, a speed and a radius at least 0, and
    /// every point and reach within ±`max` (the spec coordinates' range); a motion names at
    /// least one path, a pivot goes with keyframes, and an orbit about the instance's own
    /// centre needs a radius. Keyframes any distance apart are accepted (`key_fraction`).
    pub fn problem(&self, frames: u32, dt: f64, max: f64) -> Option<(String, String)> {
        let bad = |field: &str, message: String| Some((field.to_string(), message));
        let point = |field: &str, p: DVec3| {
            (!p.is_finite() || p.abs().max_element() > max).then(|| {
                (
                    field.to_string(),
                    format!("{} must be finite, within ±{max:e}", show(p)),
                )
            })
        };
        let axis = |field: &str, a: DVec3| {
            a.try_normalize().is_none().then(|| {
                (
                    field.to_string(),
                    format!("{} must be finite and of non-zero length", show(a)),
                )
            })
        };
        if self.is_empty() {
            return bad(
                "",
                "names no path: give `keyframes`, `orbit`, `tumble` or `walk`".into(),
            );
        }
        for (i, k) in self.keyframes.iter().enumerate() {
            let at = |f: &str| format!("keyframes[{i}].{f}");
            if !k.time.is_finite() {
                return bad(&at("time"), format!("{} must be finite", k.time));
            }
            if let Some(prev) = i.checked_sub(1).map(|j| self.keyframes[j].time) {
                if k.time <= prev {
                    return bad(
                        &at("time"),
                        format!(
                            "{} is not after keyframes[{}].time {prev}: times must increase \
                             strictly (sorted, none twice)",
                            k.time,
                            i - 1
                        ),
                    );
                }
            }
            if let Some(p) = point(&at("translate"), k.translate) {
                return Some(p);
            }
            if !k.rotate_deg.is_finite() {
                return bad(
                    &at("rotate_deg"),
                    format!("{} must be finite", show(k.rotate_deg)),
                );
            }
        }
        if let Some(p) = self.pivot {
            if self.keyframes.is_empty() {
                return bad(
                    "pivot",
                    "turns the keyframes' rotations: give `keyframes`".into(),
                );
            }
            if let Some(e) = point("pivot", p) {
                return Some(e);
            }
        }
        // The last frame's time, as [`Self::pose`] forms it (`frame · dt`).
        let end = frames.saturating_sub(1) as f64 * dt;
        if let Some(o) = &self.orbit {
            if let Some(e) = axis("orbit.axis", o.axis) {
                return Some(e);
            }
            if let Some(e) = o.center.and_then(|c| point("orbit.center", c)) {
                return Some(e);
            }
            match o.radius {
                Some(r) if !(r >= 0.0 && r <= max) => {
                    return bad(
                        "orbit.radius",
                        format!("{r} must be at least 0, at most {max:e}"),
                    )
                }
                None if o.center.is_none() => {
                    return bad(
                        "orbit",
                        "an orbit about the instance's own centre needs a `radius`".into(),
                    )
                }
                _ => {}
            }
            if !(o.period.is_finite() && o.period != 0.0) {
                return bad(
                    "orbit.period",
                    format!("{} must be finite and not 0", o.period),
                );
            }
            // The turns t / period at the last frame: a period so short that they overflow
            // would turn every pose's angle (and the scene's bounds) to NaN.
            let turns = end / o.period;
            if !turns.is_finite() {
                return bad(
                    "orbit.period",
                    format!(
                        "{:e} s makes {turns} turns over the animation's {end} s: the turns \
                         must be finite",
                        o.period
                    ),
                );
            }
            if !o.phase_deg.is_finite() {
                return bad("orbit.phase_deg", format!("{} must be finite", o.phase_deg));
            }
        }
        if let Some(tu) = &self.tumble {
            if !(tu.rate_deg * end).is_finite() {
                return bad(
                    "tumble.rate_deg",
                    format!("{} must be finite (over {end} s too)", tu.rate_deg),
                );
            }
            if let Some(e) = tu.axis.and_then(|a| axis("tumble.axis", a)) {
                return Some(e);
            }
        }
        if let Some(w) = &self.walk {
            if !(w.speed >= 0.0 && w.speed.is_finite()) {
                return bad(
                    "walk.speed",
                    format!("{} must be at least 0 and finite", w.speed),
                );
            }
            let step = w.speed * dt;
            if !step.is_finite() {
                return bad(
                    "walk.speed",
                    format!(
                        "{:e} makes a step of {step} over a time step of {dt:e} s: it must be finite",
                        w.speed
                    ),
                );
            }
            if let Some(e) = w.plane_normal.and_then(|n| axis("walk.plane_normal", n)) {
                return Some(e);
            }
        }
        let reach = self.reach(frames, dt);
        if reach.is_nan() || reach > max {
            return bad(
                "",
                format!(
                    "moves the instance up to {reach:e} over {frames} frames: past ±{max:e}, the \
                     spec coordinates' range"
                ),
            );
        }
        None
    }
}

#[cfg(test)]
#[path = "motion_tests.rs"]
mod tests;
