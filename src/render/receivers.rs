//! Receiver points: where vertex AO is evaluated.

use crate::geometry::Scene;
use glam::Vec3;

/// Receiver points and normals of a scene, world space, concatenated over receivers.
pub struct Receivers {
    pub points: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// Per receiver: (instance index, first point, point count).
    pub ranges: Vec<(usize, usize, usize)>,
}

impl Receivers {
    pub fn of(scene: &Scene) -> Receivers {
        let (mut points, mut normals, mut ranges) = (Vec::new(), Vec::new(), Vec::new());
        for (i, inst) in scene.receivers() {
            let start = points.len();
            for (p, n) in inst.mesh.positions.iter().zip(&inst.mesh.normals) {
                points.push(inst.transform.to_world_point(*p));
                normals.push(inst.transform.to_world_dir(*n).normalize());
            }
            ranges.push((i, start, points.len() - start));
        }
        Receivers {
            points,
            normals,
            ranges,
        }
    }

    /// Per instance: its slice of `ao` (None for non-receivers), for shading.
    pub fn split(&self, scene: &Scene, ao: &[f32]) -> Vec<Option<Vec<f32>>> {
        let mut out = vec![None; scene.instances.len()];
        for &(i, s, n) in &self.ranges {
            out[i] = Some(ao[s..s + n].to_vec());
        }
        out
    }
}
