//! Evaluation points of the render kinds, and the images that show their values.
//!
//! - At the receivers' vertices ([`EvalPoints::vertices`], the 2008 paper's vertex AO), shown
//!   Gouraud-interpolated over the receivers' triangles;
//! - at the receiver pixels of a G-buffer ([`EvalPoints::pixels`], the 2010 paper's per-pixel
//!   AO), one point per pixel that sees a receiver, shown at that pixel.
//!
//! Both then follow the contact convention of [`super::contact`]: points that lie on another
//! surface are moved in front of it and marked as crease points.

use super::ao::instance_epsilon;
use super::contact::separate_contacts_each;
use super::estimator::Points;
use super::image::{GrayImage, Image, ImageChannels};
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
    /// The ray offset of each point: its instance's ([`instance_epsilon`]).
    pub offsets: Vec<f32>,
    /// The ray origins, `points[i] + offsets[i] · normals[i]`: what an estimator evaluates at
    /// ([`Self::at`], with an estimator offset of 0).
    pub origins: Vec<Vec3>,
    /// Whether each point touches another surface ([`super::contact`]).
    pub crease: Vec<bool>,
    pub support: Support,
}

impl EvalPoints {
    /// Every receiver vertex of `scene`, separated from touching surfaces by its instance's
    /// offset.
    pub fn vertices(scene: &Scene) -> EvalPoints {
        let r = Receivers::of(scene);
        let (points, normals) = (r.points.clone(), r.normals.clone());
        let mut offsets = vec![0.0; points.len()];
        for &(inst, start, count) in &r.ranges {
            offsets[start..start + count].fill(instance_epsilon(&scene.instances[inst]));
        }
        Self::separated(scene, points, normals, offsets, Support::Vertices(r))
    }

    /// The surface point of every pixel of `gbuf` that sees a receiver, separated from
    /// touching surfaces by its instance's offset.
    pub fn pixels(scene: &Scene, gbuf: &GBuffer) -> EvalPoints {
        let eps: Vec<Option<f32>> = scene
            .instances
            .iter()
            .map(|i| i.receiver.then(|| instance_epsilon(i)))
            .collect();
        let (mut points, mut normals, mut offsets, mut pixels) = (vec![], vec![], vec![], vec![]);
        for (i, h) in gbuf.hits.iter().enumerate() {
            if let Some((h, e)) = h.and_then(|h| Some((h, eps[h.instance as usize]?))) {
                points.push(h.position);
                normals.push(h.normal);
                offsets.push(e);
                pixels.push(i);
            }
        }
        Self::separated(scene, points, normals, offsets, Support::Pixels(pixels))
    }

    fn separated(
        scene: &Scene,
        points: Vec<Vec3>,
        normals: Vec<Vec3>,
        offsets: Vec<f32>,
        support: Support,
    ) -> EvalPoints {
        let all: Vec<[Vec3; 3]> = scene
            .instances
            .iter()
            .flat_map(|i| i.world_triangles())
            .collect();
        let contacts = separate_contacts_each(&points, &normals, &all, &offsets);
        let origins = contacts
            .points
            .iter()
            .zip(&normals)
            .zip(&offsets)
            .map(|((&p, &n), &o)| p + o * n)
            .collect();
        EvalPoints {
            points: contacts.points,
            normals,
            offsets,
            origins,
            crease: contacts.crease,
            support,
        }
    }

    /// The ray origins and normals, for an [`super::estimator::Estimator`] whose offset is 0
    /// (each point is already moved off its surface by its own instance's offset).
    pub fn at(&self) -> Points<'_> {
        Points {
            points: &self.origins,
            normals: &self.normals,
        }
    }

    /// The largest ray offset of the points (0 without points).
    pub fn max_offset(&self) -> f32 {
        self.offsets.iter().copied().fold(0.0, f32::max)
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

    /// The image of `values` (`channels` per point, point-major) seen through `gbuf`, showing
    /// the channels `show` picks (grey, or red, green and blue: each a plane made as
    /// [`Self::image`] makes it), and the mask of the pixels that show a value. One channel
    /// shown as grey is [`Self::image`] of the values.
    ///
    /// # Panics
    /// If `values` is not `channels` per point or `show` picks a channel past `channels`.
    pub fn values_image(
        &self,
        scene: &Scene,
        gbuf: &GBuffer,
        values: &[f32],
        channels: usize,
        show: ImageChannels,
    ) -> (Image, Vec<bool>) {
        assert_eq!(
            values.len(),
            self.len() * channels,
            "image: {channels} values per point"
        );
        assert!(show.shown().iter().all(|&c| c < channels));
        if channels == 1 {
            let (img, mask) = self.image(scene, gbuf, values);
            return (img.into(), mask);
        }
        let mut mask = Vec::new();
        let planes = show
            .shown()
            .iter()
            .map(|&c| {
                let plane: Vec<f32> = values.iter().skip(c).step_by(channels).copied().collect();
                let (img, m) = self.image(scene, gbuf, &plane);
                mask = m;
                img
            })
            .collect();
        (Image::interleave(planes), mask)
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
