//! Evaluation points of the render kinds, and the images that show their values.
//!
//! - At the receivers' vertices ([`EvalPoints::vertices`], the 2008 paper's vertex AO), shown
//!   Gouraud-interpolated over the receivers' triangles;
//! - at the receiver pixels of a G-buffer ([`EvalPoints::pixels`], the 2010 paper's per-pixel
//!   AO), one point per pixel that sees a receiver, shown at that pixel.
//!
//! Both then follow the contact convention of [`super::contact`]: points that lie on another
//! surface are moved in front of it and marked as crease points.

use super::contact::separate_contacts;
use super::estimator::Points;
use super::image::GrayImage;
use super::primary::{shade_vertex_ao, PixelHit};
use super::receivers::Receivers;
use crate::geometry::Scene;
use glam::Vec3;

/// A G-buffer: one optional hit per pixel, row-major, row 0 at the top
/// ([`super::primary::gbuffer`]).
#[derive(Clone, Debug)]
pub struct GBuffer {
    pub hits: Vec<Option<PixelHit>>,
    pub width: u32,
    pub height: u32,
}

/// Where the points come from.
pub enum Support {
    /// The receivers' vertices, concatenated over receivers.
    Vertices(Receivers),
    /// Receiver pixels: point `j` is pixel `pixels[j]` of the G-buffer.
    Pixels(Vec<usize>),
}

/// The points a render kind evaluates.
pub struct EvalPoints {
    /// Positions, after the contact convention.
    pub points: Vec<Vec3>,
    /// Unit normals.
    pub normals: Vec<Vec3>,
    /// Whether each point touches another surface ([`super::contact`]).
    pub crease: Vec<bool>,
    pub support: Support,
}

impl EvalPoints {
    /// Every receiver vertex of `scene`, separated from touching surfaces by `offset`.
    pub fn vertices(scene: &Scene, offset: f32) -> EvalPoints {
        let r = Receivers::of(scene);
        let (points, normals) = (r.points.clone(), r.normals.clone());
        Self::separated(scene, points, normals, Support::Vertices(r), offset)
    }

    /// The surface point of every pixel of `gbuf` that sees a receiver, separated from
    /// touching surfaces by `offset`.
    pub fn pixels(scene: &Scene, gbuf: &GBuffer, offset: f32) -> EvalPoints {
        let (mut points, mut normals, mut pixels) = (vec![], vec![], vec![]);
        for (i, h) in gbuf.hits.iter().enumerate() {
            if let Some(h) = h.filter(|h| scene.instances[h.instance as usize].receiver) {
                points.push(h.position);
                normals.push(h.normal);
                pixels.push(i);
            }
        }
        Self::separated(scene, points, normals, Support::Pixels(pixels), offset)
    }

    fn separated(
        scene: &Scene,
        points: Vec<Vec3>,
        normals: Vec<Vec3>,
        support: Support,
        offset: f32,
    ) -> EvalPoints {
        let all: Vec<[Vec3; 3]> = scene
            .instances
            .iter()
            .flat_map(|i| i.world_triangles())
            .collect();
        let contacts = separate_contacts(&points, &normals, &all, offset, offset);
        EvalPoints {
            points: contacts.points,
            normals,
            crease: contacts.crease,
            support,
        }
    }

    /// The points and normals, for an [`super::estimator::Estimator`].
    pub fn at(&self) -> Points<'_> {
        Points {
            points: &self.points,
            normals: &self.normals,
        }
    }

    /// The number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The number of crease points.
    pub fn crease_count(&self) -> usize {
        self.crease.iter().filter(|&&c| c).count()
    }

    /// The receivers, when the points are their vertices.
    pub fn receivers(&self) -> Option<&Receivers> {
        match &self.support {
            Support::Vertices(r) => Some(r),
            Support::Pixels(_) => None,
        }
    }

    /// The image of `values` (one per point) seen through `gbuf`, and the mask of the pixels
    /// that show a value (the pixels an image RMS is computed over). Other surfaces are shaded
    /// with the fixed light of [`shade_vertex_ao`], the same in every image.
    pub fn image(&self, scene: &Scene, gbuf: &GBuffer, values: &[f32]) -> (GrayImage, Vec<bool>) {
        let (w, h) = (gbuf.width, gbuf.height);
        match &self.support {
            Support::Vertices(r) => {
                shade_vertex_ao(scene, &gbuf.hits, w, h, &r.split(scene, values))
            }
            Support::Pixels(pixels) => {
                let none = vec![None; scene.instances.len()];
                let (mut img, mut mask) = shade_vertex_ao(scene, &gbuf.hits, w, h, &none);
                for (j, &px) in pixels.iter().enumerate() {
                    img.data[px] = values[j];
                    mask[px] = true;
                }
                (img, mask)
            }
        }
    }
}
