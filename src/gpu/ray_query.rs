//! Hardware ray queries as a GPU visibility: what engines answer visibility with today, a
//! top-level acceleration structure (TLAS) over instanced bottom-level ones (BLAS), walked by
//! the device (wgpu's `EXPERIMENTAL_RAY_QUERY`, Vulkan `VK_KHR_ray_query`), against which the
//! presampled field of Gaitatzes, Andreadis, Papaioannou and Chrysanthou (WSCG 2010) is
//! measured on the GPU. Beyond the papers: they compare with no ray caster of this kind.
//!
//! - One BLAS per mesh, built once in model space: its triangles sorted in the Morton order of
//!   their centroids first (lavapipe builds its BVH in index order: unsorted, its traces run
//!   many times slower), flagged opaque (else hits stay candidates and the committed result
//!   is a miss). Every mesh's triangles share one buffer (BLAS input and storage, three
//!   `vec4` a triangle with the original index in the first `w`), each BLAS built from its
//!   range.
//! - A TLAS over the instances, rebuilt by [`RayQueryScene::place`] with each instance's
//!   transform (wgpu 30 turns an update into a full build: N transforms); an instance's id
//!   is the TLAS instance's custom data (24 bits), not its slot.
//! - `occluded`: any hit, the walk ended by the first (`RAY_FLAG_TERMINATE_ON_FIRST_HIT`);
//!   `surface_hit`: the closest hit and its triangle's model-space normal moved to world space
//!   by the transpose of the instance's world-to-object matrix, as the CPU two-level caster
//!   moves its normals (shaders/ray_query.wgsl).
//!
//! Both windings hit and `tmin <= t <= tmax` is inclusive, as [`crate::trace::Tracer`]. The
//! integrands of src/gpu/integrand.rs run on it as on any [`GpuVisibility`]. Opened only where
//! the adapter offers ray queries ([`GpuContext::ray_query_support`]); elsewhere
//! [`RayQueryScene::new`] refuses with [`GpuError::Unsupported`], saying why.

use super::context::GpuContext;
use super::shadow_rays::check_binding;
use super::tracer::{
    any_hits, closest_hits, ray_queries, triangle_records, CasterHeaderGpu, RayQueries,
    CASTER_HEADER_WGSL, RAY_QUERIES_WGSL,
};
use super::visibility::{GpuVisibility, Kernels, VisibilityGroup, READ_ONLY_STORAGE};
use super::{GpuError, GpuTiming};
use crate::trace::RayQuery;
use glam::{DVec3, Mat4, Vec3};
use obvhs::ploc::morton::morton_encode_u64_unorm;
use std::time::{Duration, Instant};
use wgpu::util::DeviceExt;

/// The visibility's own queries (its closest-hit words: shaders/ray_query_queries.wgsl).
const QUERIES: RayQueries = ray_queries(&[
    RAY_QUERIES_WGSL,
    include_str!("../../shaders/ray_query_queries.wgsl"),
]);

/// Words a closest-hit query writes per ray (shaders/ray_query_queries.wgsl).
const CLOSEST_WORDS: u32 = 6;
/// The largest instance id a TLAS instance's custom data holds (24 bits).
const MAX_CUSTOM_DATA: usize = (1 << 24) - 1;

/// A closest hit found by a ray query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayQueryHit {
    /// Distance along the ray.
    pub t: f32,
    /// The instance hit (its index in the list placed).
    pub instance: u32,
    /// The triangle hit: its index in its mesh, as given to [`RayQueryScene::new`].
    pub triangle: u32,
    /// The triangle's unit normal in world space (`cross(v1 - v0, v2 - v0)` of its model-space
    /// vertices, moved by the instance's transform).
    pub normal: Vec3,
}

/// Instanced meshes behind hardware ray queries: a BLAS per mesh, a TLAS of the instances (see
/// the module documentation).
pub struct RayQueryScene<'a> {
    ctx: &'a GpuContext,
    /// The header, then the TLAS, the triangles and the instances' first triangles, bound at
    /// each call.
    group: VisibilityGroup,
    placement: Placement,
    /// Every mesh's triangles, sorted, three vec4 each.
    triangles: wgpu::Buffer,
    tlas: wgpu::Tlas,
    instance_count: u32,
    kernels: Kernels,
    setup: Duration,
}

/// What placing instances reads of a [`RayQueryScene`].
struct Placement {
    /// Per mesh: its BLAS (none for a mesh without triangles) and its first triangle in
    /// `triangles`.
    blas: Vec<Option<wgpu::Blas>>,
    first_triangle: Vec<u32>,
    /// Per instance (by id): its mesh's first triangle.
    instance_first: wgpu::Buffer,
}

impl Placement {
    /// Fills the TLAS's slots with `instances` (empty meshes left out; the custom data the
    /// instance's id), writes each instance's first triangle, builds `blas` and the TLAS in
    /// one submission and waits for it; the instances placed.
    fn build(
        &self,
        ctx: &GpuContext,
        tlas: &mut wgpu::Tlas,
        blas: &[wgpu::BlasBuildEntry],
        instances: &[(usize, Mat4)],
    ) -> Result<u32, GpuError> {
        let slots = tlas.get().len();
        if instances.len() > slots {
            return Err(GpuError::Invalid(format!(
                "{} instances placed in a TLAS made for {slots}",
                instances.len()
            )));
        }
        check_instances(instances, self.first_triangle.len())?;
        let mut firsts = Vec::with_capacity(instances.len());
        let mut slot = 0;
        for (id, (mesh, m)) in instances.iter().enumerate() {
            firsts.push(self.first_triangle[*mesh]);
            if let Some(b) = &self.blas[*mesh] {
                tlas[slot] = Some(wgpu::TlasInstance::new(b, rows_3x4(m), id as u32, 0xff));
                slot += 1;
            }
        }
        for s in slot..slots {
            tlas[s] = None;
        }
        if !firsts.is_empty() {
            (ctx.queue).write_buffer(&self.instance_first, 0, bytemuck::cast_slice(&firsts));
        }
        let mut encoder =
            (ctx.device).create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        encoder.build_acceleration_structures(blas, [&*tlas]);
        ctx.queue.submit([encoder.finish()]);
        ctx.wait("waiting for the acceleration structures' build")?;
        Ok(instances.len() as u32)
    }
}

/// Every instance names one of `meshes` meshes and has a finite transform; else the first
/// that does not, named.
fn check_instances(instances: &[(usize, Mat4)], meshes: usize) -> Result<(), GpuError> {
    for (id, (mesh, m)) in instances.iter().enumerate() {
        if *mesh >= meshes {
            return Err(GpuError::Invalid(format!(
                "instance {id}: mesh {mesh} of {meshes}"
            )));
        }
        if !m.is_finite() {
            return Err(GpuError::Invalid(format!(
                "instance {id}: its transform must be finite"
            )));
        }
    }
    Ok(())
}

/// `m`'s affine part as wgpu's 3 × 4 row-major matrix.
fn rows_3x4(m: &Mat4) -> [f32; 12] {
    let c = [m.x_axis, m.y_axis, m.z_axis, m.w_axis];
    std::array::from_fn(|i| c[i % 4][i / 4])
}

/// The largest unit coordinate the Morton code keeps apart from 1 (21 bits a coordinate).
const BELOW_ONE: f64 = 1.0 - 1.0 / (1u64 << 21) as f64;

/// The order of `triangles` by the Morton code of their centroids over the centroids' box
/// (ties by index).
pub fn morton_order(triangles: &[[Vec3; 3]]) -> Vec<u32> {
    let centroids: Vec<DVec3> = triangles
        .iter()
        .map(|t| (t[0].as_dvec3() + t[1].as_dvec3() + t[2].as_dvec3()) / 3.0)
        .collect();
    let (lo, hi) = centroids.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &c| (lo.min(c), hi.max(c)),
    );
    let scale = 1.0 / (hi - lo).max(DVec3::splat(f64::MIN_POSITIVE));
    let mut keyed: Vec<(u64, u32)> = centroids
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            // Below 1: obvhs maps [0, 1) onto 21 bits a coordinate, and 1 would wrap to 0.
            let u = ((c - lo) * scale).clamp(DVec3::ZERO, DVec3::splat(BELOW_ONE));
            (morton_encode_u64_unorm(u), i as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

impl<'a> RayQueryScene<'a> {
    /// Builds a BLAS per mesh of `meshes` (model-space triangles) and the TLAS of
    /// `instances` (each: its mesh and its model-to-world transform, affine), and compiles
    /// the queries.
    ///
    /// Errors: [`GpuError::Unsupported`] where the device has no ray queries;
    /// [`GpuError::Invalid`] for a vertex or transform not finite, or a mesh index out of
    /// range; [`GpuError::TooLarge`] past the adapter's acceleration-structure or binding
    /// limits, by name, before any upload.
    pub fn new(
        ctx: &'a GpuContext,
        meshes: &[Vec<[Vec3; 3]>],
        instances: &[(usize, Mat4)],
    ) -> Result<Self, GpuError> {
        let start = Instant::now();
        ctx.ray_query_support().map_err(GpuError::Unsupported)?;
        let limits = ctx.limits();
        for (m, tris) in meshes.iter().enumerate() {
            if tris.iter().flatten().any(|v| !v.is_finite()) {
                return Err(GpuError::Invalid(format!(
                    "mesh {m}: triangle vertices must be finite"
                )));
            }
            if tris.len() as u64 > limits.max_blas_primitive_count as u64 {
                return Err(GpuError::TooLarge {
                    what: format!("the BLAS of mesh {m} ({} triangles)", tris.len()),
                    need: tris.len() as u64,
                    limit: limits.max_blas_primitive_count as u64,
                    limit_name: "max_blas_primitive_count",
                });
            }
        }
        check_instances(instances, meshes.len())?;
        let total: usize = meshes.iter().map(Vec::len).sum();
        check_binding::<[[f32; 4]; 3]>(ctx, "triangles of the meshes", total)?;
        let max_instances = instances.len().max(1);
        if max_instances > MAX_CUSTOM_DATA
            || max_instances as u64 > limits.max_tlas_instance_count as u64
        {
            return Err(GpuError::TooLarge {
                what: format!("the TLAS of {} instances", instances.len()),
                need: max_instances as u64,
                limit: (limits.max_tlas_instance_count as u64).min(MAX_CUSTOM_DATA as u64),
                limit_name: "max_tlas_instance_count",
            });
        }
        // Every mesh's triangles in Morton order, one after the other.
        let mut data: Vec<[f32; 4]> = Vec::with_capacity(3 * total);
        let mut first_triangle = Vec::with_capacity(meshes.len());
        for tris in meshes {
            first_triangle.push((data.len() / 3) as u32);
            data.extend(triangle_records(tris, &morton_order(tris)));
        }
        if data.is_empty() {
            data.resize(3, [0.0; 4]);
        }
        let device = &ctx.device;
        let triangles = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ray query triangles"),
            contents: bytemuck::cast_slice(&data),
            usage: wgpu::BufferUsages::BLAS_INPUT | wgpu::BufferUsages::STORAGE,
        });
        let sizes: Vec<Option<wgpu::BlasTriangleGeometrySizeDescriptor>> = meshes
            .iter()
            .map(|tris| {
                (!tris.is_empty()).then(|| wgpu::BlasTriangleGeometrySizeDescriptor {
                    vertex_format: wgpu::VertexFormat::Float32x3,
                    vertex_count: 3 * tris.len() as u32,
                    index_format: None,
                    index_count: None,
                    flags: wgpu::AccelerationStructureGeometryFlags::OPAQUE,
                })
            })
            .collect();
        let blas: Vec<Option<wgpu::Blas>> = sizes
            .iter()
            .map(|size| {
                size.as_ref().map(|size| {
                    device.create_blas(
                        &wgpu::CreateBlasDescriptor {
                            label: Some("ray query mesh"),
                            flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
                        },
                        wgpu::BlasGeometrySizeDescriptors::Triangles {
                            descriptors: vec![size.clone()],
                        },
                    )
                })
            })
            .collect();
        let mut tlas = device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some("ray query instances"),
            max_instances: max_instances as u32,
            flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        let instance_first = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ray query instance triangles"),
            size: 4 * max_instances as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = VisibilityGroup::with_bindings(
            ctx,
            "ray query",
            &[],
            &[
                wgpu::BindingType::AccelerationStructure {
                    vertex_return: false,
                },
                READ_ONLY_STORAGE,
                READ_ONLY_STORAGE,
            ],
        );
        let placement = Placement {
            blas,
            first_triangle,
            instance_first,
        };
        // The BLASes are built with the first TLAS, in one submission (a BLAS built without
        // the TLAS that references it is refused at submit by wgpu 30).
        let entries: Vec<wgpu::BlasBuildEntry> = (placement.blas.iter().zip(&sizes))
            .zip(&placement.first_triangle)
            .filter_map(|((b, size), &first)| {
                Some(wgpu::BlasBuildEntry {
                    blas: b.as_ref()?,
                    geometry: wgpu::BlasGeometries::TriangleGeometries(vec![
                        wgpu::BlasTriangleGeometry {
                            size: size.as_ref()?,
                            vertex_buffer: &triangles,
                            first_vertex: 3 * first,
                            vertex_stride: 16,
                            index_buffer: None,
                            first_index: None,
                            transform_buffer: None,
                            transform_buffer_offset: None,
                        },
                    ]),
                })
            })
            .collect();
        let instance_count = placement.build(ctx, &mut tlas, &entries, instances)?;
        drop(entries);
        let scene = RayQueryScene {
            ctx,
            group,
            placement,
            triangles,
            tlas,
            instance_count,
            kernels: Kernels::new(super::loop_budget::DEFAULT_RAYS_PER_INVOCATION),
            setup: Duration::ZERO,
        };
        QUERIES.precompile(&scene, &scene.kernels)?;
        Ok(RayQueryScene {
            setup: start.elapsed(),
            ..scene
        })
    }

    /// Host time of the sort, the uploads, the first build and the shader compilation.
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// Instances the TLAS holds room for (as many as [`Self::new`] was given, at least one).
    pub fn max_instances(&self) -> usize {
        self.tlas.get().len()
    }

    /// Moves the instances: the TLAS rebuilt over `instances` (each: its mesh and its
    /// model-to-world transform; at most [`Self::max_instances`]), waiting until the device
    /// has built it, so that the time of this call is the frame's update.
    pub fn place(&mut self, instances: &[(usize, Mat4)]) -> Result<(), GpuError> {
        let placed = &self.placement;
        self.instance_count = placed.build(self.ctx, &mut self.tlas, &[], instances)?;
        Ok(())
    }

    /// Whether each ray hits any triangle with `tmin <= t <= tmax`.
    pub fn any_hits(&self, rays: &[RayQuery]) -> Result<(Vec<bool>, GpuTiming), GpuError> {
        any_hits(self, &self.kernels, &QUERIES.any, rays)
    }

    /// The closest hit of each ray with `tmin <= t <= tmax`.
    pub fn closest_hits(
        &self,
        rays: &[RayQuery],
    ) -> Result<(Vec<Option<RayQueryHit>>, GpuTiming), GpuError> {
        let f = f32::from_bits;
        closest_hits(
            self,
            &self.kernels,
            &QUERIES.closest,
            rays,
            CLOSEST_WORDS,
            |w| {
                (w[1] != u32::MAX).then(|| RayQueryHit {
                    t: f(w[0]),
                    triangle: w[1],
                    normal: Vec3::new(f(w[2]), f(w[3]), f(w[4])),
                    instance: w[5],
                })
            },
        )
    }
}

impl GpuVisibility for RayQueryScene<'_> {
    fn context(&self) -> &GpuContext {
        self.ctx
    }

    fn wgsl(&self, _: u32) -> String {
        [
            CASTER_HEADER_WGSL,
            include_str!("../../shaders/ray_query.wgsl"),
        ]
        .concat()
    }

    fn directives(&self) -> &'static str {
        "enable wgpu_ray_query;\n"
    }

    fn layout(&self) -> &wgpu::BindGroupLayout {
        self.group.layout()
    }

    fn bind_group(&self) -> wgpu::BindGroup {
        let header = CasterHeaderGpu {
            instance_count: self.instance_count,
            ..Default::default()
        };
        self.group.bind_with(
            self.ctx,
            bytemuck::bytes_of(&header),
            &[
                wgpu::BindingResource::AccelerationStructure(&self.tlas),
                self.triangles.as_entire_binding(),
                self.placement.instance_first.as_entire_binding(),
            ],
        )
    }

    fn kernels(&self) -> &Kernels {
        &self.kernels
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_3x4_is_the_affine_part_row_major() {
        let m = Mat4::from_cols_array(&[
            1.0, 2.0, 3.0, 0.0, 4.0, 5.0, 6.0, 0.0, 7.0, 8.0, 9.0, 0.0, 10.0, 11.0, 12.0, 1.0,
        ]);
        // Row 0 is the x components of the columns, then the translation's x.
        assert_eq!(
            rows_3x4(&m),
            [1.0, 4.0, 7.0, 10.0, 2.0, 5.0, 8.0, 11.0, 3.0, 6.0, 9.0, 12.0]
        );
        let p = Vec3::new(0.5, -1.0, 2.0);
        let r = rows_3x4(&m);
        let by_rows = Vec3::new(
            r[0] * p.x + r[1] * p.y + r[2] * p.z + r[3],
            r[4] * p.x + r[5] * p.y + r[6] * p.z + r[7],
            r[8] * p.x + r[9] * p.y + r[10] * p.z + r[11],
        );
        assert_eq!(by_rows, m.transform_point3(p));
    }

    #[test]
    fn morton_order_is_a_permutation_that_groups_neighbours() {
        // A row of triangles along x given in a shuffled order comes back sorted by x.
        let tri = |x: f32| {
            [
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 0.5, 0.0, 0.0),
                Vec3::Y,
            ]
        };
        let xs = [5.0, 1.0, 7.0, 0.0, 3.0, 6.0, 2.0, 4.0];
        let tris: Vec<[Vec3; 3]> = xs.iter().map(|&x| tri(x)).collect();
        let order = morton_order(&tris);
        let sorted: Vec<f32> = order.iter().map(|&i| xs[i as usize]).collect();
        assert_eq!(sorted, [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        assert!(morton_order(&[]).is_empty());
        assert_eq!(morton_order(&[tri(1.0)]), [0]);
    }
}
