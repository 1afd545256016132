//! One field binding that every field kernel reuses: a set of [`FieldInstance`]s packed and
//! uploaded once, in either [`FieldLayout`], and bound as bind group [`FIELD_GROUP`] (Gaitatzes
//! et al., WSCG 2008 / WSCG 2010: the lookup of placed presampled visibility fields).
//!
//! [`FieldBinding`] owns everything the WGSL lookup (`instance_occludes`, `field_sample` in
//! shaders/field_lookup.wgsl) reads:
//!
//! - the per-instance records ([`super::FieldInstanceGpu`]), the shared tables (sphere points,
//!   1-bit means) and the sphere triangulations followed by the owner and texel tables
//!   ([`PackedFields`]; shaders/lookup_tables.wgsl);
//! - the stored distances: storage-buffer windows of at most the adapter's binding size, or the
//!   tiles of one 3D texture ([`FieldTexture`]);
//! - the bind-group layout and the bind group of group [`FIELD_GROUP`] holding them;
//! - the WGSL text of the lookup: the group's declarations and the layout's `load_word` /
//!   `load_element`, then frame, sphere points, layouts, lookup, lookup tables and the
//!   layout's `load_distance` ([`FieldBinding::shader_source`]).
//!
//! The field visibility (src/gpu/field_kernel.rs) is this group with its header and, for
//! reflections, the normal fields; with its own top level ([`FieldBindingOptions::top_level`])
//! the BVH over the instances' spheres (the CPU's [`SphereBvh`], rebuilt on the host and
//! uploaded whenever the instances move: shaders/field_top_level.wgsl) answers `occluded` and
//! `surface_hit` instead of the loops over every instance.
//!
//! Group [`FIELD_GROUP`]'s bindings: 0 the visibility's header (`field_params`), 1 `tables`,
//! 2 `mesh`, 3 `instances`, 4 `normals` (where bound), then the windows `win0`, `win1`, …
//! (storage layout) or `field_tex` (texture layout), then `sphere_nodes` (with the top level).

use super::context::{entry, layout_entry, uniform_layout_entry, GpuContext};
use super::field_data::{field_words, placed, FieldInstanceGpu, PackedFields};
use super::texture::FieldTexture;
use super::visibility::READ_ONLY_STORAGE;
use super::GpuError;
use crate::field::scene::{FieldInstance, MAY_MEET_SLACK};
use crate::field::sphere_bvh::SphereBvh;
use crate::field::VisibilityField;
use std::sync::Arc;

/// The bind group the field bindings occupy; group 0 is the integrand's.
pub(crate) const FIELD_GROUP: u32 = 1;

/// Storage bindings of the field group before the stored distances (tables, mesh, instances).
const TABLE_BUFFERS: u32 = 3;
/// The normal fields' binding (shaders/field_surface.wgsl).
const NORMALS_BINDING: u32 = 4;
/// The first binding of the stored distances.
const FIRST_STORE_BINDING: u32 = 5;

/// How the stored distances are bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FieldLayout {
    /// The stored words as they are on the host, in storage buffers bound in windows of at
    /// most the adapter's `max_storage_buffer_binding_size`.
    StorageBuffers,
    /// The 2010 paper's packing: maps as tiles of the slices of a 3D texture (r32float, r16uint,
    /// r8uint by precision; 1-bit maps as r32uint words), several maps per slice.
    Texture3d,
}

/// How a [`FieldBinding`] lays out and sizes the stored distances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FieldBindingOptions {
    pub layout: FieldLayout,
    /// Largest window in bytes (storage layout); `None`: the adapter's binding limit.
    pub window_bytes: Option<u64>,
    /// Largest texture depth (texture layout); `None`: the adapter's limit.
    pub max_texture_depth: Option<u32>,
    /// Storage buffers the kernel binds besides the field's own (group 0, the normal fields):
    /// the windows get what is left of the adapter's `max_storage_buffers_per_shader_stage`.
    pub kernel_storage_buffers: u32,
    /// Upload each field's owner and texel tables and read them before the ring search and
    /// the concentric map (`OWNER_TABLES`, `TEXEL_TABLES` in the WGSL lookup).
    pub lookup_tables: bool,
    /// Bind the instances' own top level, a BVH over their spheres, and walk it in `occluded`
    /// and `surface_hit` (one more storage buffer, counted here, not in
    /// `kernel_storage_buffers`).
    pub top_level: bool,
}

/// Twin of WGSL `SphereNode` (shaders/field_top_level.wgsl): one node of the instances' own
/// top level ([`SphereBvh::flat_nodes`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct SphereNodeGpu {
    lo: [f32; 3],
    /// A leaf's instance, or an inner node's first child.
    index: u32,
    hi: [f32; 3],
    /// 1 for a leaf, 0 for an inner node.
    leaf: u32,
}
const _: () = assert!(std::mem::size_of::<SphereNodeGpu>() == 32);
const _: () = assert!(std::mem::offset_of!(SphereNodeGpu, hi) == 16);

/// The top level's nodes over `instances` as the WGSL reads them.
fn sphere_nodes(instances: &[FieldInstance]) -> Vec<SphereNodeGpu> {
    (SphereBvh::new(instances).flat_nodes().into_iter())
        .map(|n| SphereNodeGpu {
            lo: n.lo.to_array(),
            index: n.index,
            hi: n.hi.to_array(),
            leaf: n.leaf as u32,
        })
        .collect()
}

/// The fields' stored distances on the device.
enum FieldStore {
    /// Storage windows of `window_words` words each (the last may be shorter).
    Windows {
        buffers: Vec<wgpu::Buffer>,
        window_words: usize,
    },
    /// One 3D texture and its view.
    Texture {
        texture: Box<FieldTexture>,
        view: wgpu::TextureView,
    },
}

/// The field group's resources on the device.
struct FieldResources {
    tables: wgpu::Buffer,
    mesh: wgpu::Buffer,
    instances: wgpu::Buffer,
    normals: Option<wgpu::Buffer>,
    store: FieldStore,
    /// The instances' own top level, where bound.
    top: Option<wgpu::Buffer>,
}

/// A binding of the field group: its number, type and resource.
type Binding<'a> = (u32, wgpu::BindingType, wgpu::BindingResource<'a>);

impl FieldResources {
    /// The field group's bindings after the header (a uniform at binding 0), in order.
    fn bindings(&self) -> Vec<Binding<'_>> {
        fn storage(b: u32, buffer: &wgpu::Buffer) -> Binding<'_> {
            (b, READ_ONLY_STORAGE, buffer.as_entire_binding())
        }
        let mut out = vec![
            storage(1, &self.tables),
            storage(2, &self.mesh),
            storage(3, &self.instances),
        ];
        out.extend(self.normals.iter().map(|n| storage(NORMALS_BINDING, n)));
        match &self.store {
            FieldStore::Windows { buffers, .. } => out.extend(
                (FIRST_STORE_BINDING..)
                    .zip(buffers)
                    .map(|(b, w)| storage(b, w)),
            ),
            FieldStore::Texture { texture, view } => out.push((
                FIRST_STORE_BINDING,
                wgpu::BindingType::Texture {
                    sample_type: texture.sample_type(),
                    view_dimension: wgpu::TextureViewDimension::D3,
                    multisampled: false,
                },
                wgpu::BindingResource::TextureView(view),
            )),
        }
        out.extend(self.top.iter().map(|t| storage(self.top_binding(), t)));
        out
    }

    /// Layout entries of the field group.
    fn layout_entries(&self) -> Vec<wgpu::BindGroupLayoutEntry> {
        let mut entries = vec![uniform_layout_entry(0)];
        entries.extend(
            self.bindings()
                .into_iter()
                .map(|(b, ty, _)| layout_entry(b, ty)),
        );
        entries
    }

    /// The top level's binding: after the stored distances.
    fn top_binding(&self) -> u32 {
        FIRST_STORE_BINDING
            + match &self.store {
                FieldStore::Windows { buffers, .. } => buffers.len() as u32,
                FieldStore::Texture { .. } => 1,
            }
    }

    /// Bind-group entries of the field group, in the order of [`Self::layout_entries`].
    fn entries<'b>(&'b self, header: &'b wgpu::Buffer) -> Vec<wgpu::BindGroupEntry<'b>> {
        let mut entries = vec![entry(0, header.as_entire_binding())];
        entries.extend(self.bindings().into_iter().map(|(b, _, r)| entry(b, r)));
        entries
    }

    /// The generated WGSL (the group's declarations and the layout's element loader) and the
    /// layout's `load_distance` source.
    fn prelude(&self) -> (String, &'static str) {
        let (prelude, layout) = self.store_prelude();
        let top = match self.top {
            Some(_) => format!(
                "const MAY_MEET_SLACK: f32 = {MAY_MEET_SLACK:e};\n\
                 @group({FIELD_GROUP}) @binding({}) var<storage, read> sphere_nodes: array<SphereNode>;\n",
                self.top_binding()
            ),
            None => String::new(),
        };
        (prelude + &top, layout)
    }

    fn store_prelude(&self) -> (String, &'static str) {
        match &self.store {
            FieldStore::Windows {
                buffers,
                window_words,
            } => (
                group_prelude() + &window_prelude(buffers.len(), *window_words),
                include_str!("../../shaders/field_storage.wgsl"),
            ),
            FieldStore::Texture { texture, .. } => (
                group_prelude() + &texture.prelude(FIELD_GROUP, FIRST_STORE_BINDING),
                include_str!("../../shaders/field_texture.wgsl"),
            ),
        }
    }
}

/// A set of field instances on the device, bound as group [`FIELD_GROUP`] (see the module
/// documentation).
pub(crate) struct FieldBinding {
    resources: FieldResources,
    /// Group declarations and the layout's element loader (generated).
    prelude: String,
    /// The layout's `load_distance` (shaders/field_storage.wgsl or field_texture.wgsl).
    layout_source: &'static str,
    field_bytes: u64,
    group_layout: wgpu::BindGroupLayout,
    /// The instance records as uploaded, and each instance's field: what [`Self::place`]
    /// moves and checks.
    records: Vec<FieldInstanceGpu>,
    instance_fields: Vec<Arc<VisibilityField>>,
}

impl FieldBinding {
    /// Packs `instances` (their distinct fields once each), uploads them in `opts.layout` with
    /// the normal fields' words `normals` where given, and makes the field group's layout.
    ///
    /// Errors: [`GpuError::Unsupported`] for fields the GPU lookup cannot read (Fibonacci point
    /// sets; mixed precisions in one texture), [`GpuError::TooLarge`] when the fields pass the
    /// adapter's storage bindings or texture size.
    pub fn new(
        ctx: &GpuContext,
        instances: &[FieldInstance],
        normals: Option<&[u32]>,
        opts: &FieldBindingOptions,
    ) -> Result<FieldBinding, GpuError> {
        let mut packed = PackedFields::new(instances, opts.lookup_tables)?;
        let windows_opts = FieldBindingOptions {
            kernel_storage_buffers: opts.kernel_storage_buffers + opts.top_level as u32,
            ..*opts
        };
        let (store, field_bytes) = match opts.layout {
            FieldLayout::StorageBuffers => upload_windows(ctx, &mut packed, &windows_opts)?,
            FieldLayout::Texture3d => upload_texture(ctx, &mut packed, opts)?,
        };
        let top = (opts.top_level).then(|| {
            ctx.storage_buffer(
                "sphere nodes",
                bytemuck::cast_slice(&sphere_nodes(instances)),
            )
        });
        let resources = FieldResources {
            tables: ctx.storage_buffer("tables", bytemuck::cast_slice(&packed.tables)),
            mesh: ctx.storage_buffer("sphere mesh", bytemuck::cast_slice(&packed.mesh)),
            instances: ctx.storage_buffer("instances", bytemuck::cast_slice(&packed.instances)),
            normals: normals.map(|w| ctx.storage_buffer("normal fields", bytemuck::cast_slice(w))),
            store,
            top,
        };
        let (prelude, layout_source) = resources.prelude();
        let prelude = kinds_prelude(&packed.instances) + &prelude;
        let group_layout = ctx.group_layout("field group", &resources.layout_entries());
        let instance_fields = instances.iter().map(|i| i.field.clone()).collect();
        Ok(FieldBinding {
            records: packed.instances.clone(),
            instance_fields,
            resources,
            prelude,
            layout_source,
            field_bytes,
            group_layout,
        })
    }

    /// WGSL of the field lookup: the group's declarations, the layout's element loader,
    /// sphere points, layouts, the lookup and the layout's `load_distance`, then the field
    /// visibility's `occluded` and, with the normal fields, its `surface_hit`: the loops over
    /// every instance, or the walks of the instances' own top level where it is bound.
    pub fn shader_source(&self) -> String {
        let mut parts = vec![
            self.prelude.as_str(),
            include_str!("../../shaders/sphere_points.wgsl"),
            include_str!("../../shaders/layouts.wgsl"),
            include_str!("../../shaders/field_lookup.wgsl"),
            include_str!("../../shaders/lookup_tables.wgsl"),
            self.layout_source,
            include_str!("../../shaders/field_visibility.wgsl"),
        ];
        let normals = self.resources.normals.is_some();
        if normals {
            parts.push(include_str!("../../shaders/field_surface.wgsl"));
        }
        let top = self.resources.top.is_some();
        if top {
            parts.push(include_str!("../../shaders/field_top_level.wgsl"));
            if normals {
                parts.push(include_str!("../../shaders/field_top_level_surface.wgsl"));
            }
        }
        let mode = if top { "top_level" } else { "every_sphere" };
        let mut queries = format!(
            "// The visibility's queries: {mode}.\n\
             fn occluded(o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax: f32) -> bool {{ return occluded_{mode}(o, d, tmin, tmax); }}\n"
        );
        if normals {
            queries += &format!(
                "fn surface_hit(o: vec3<f32>, d: vec3<f32>, tmax: f32) -> SurfaceHit {{ return surface_hit_{mode}(o, d, tmax); }}\n"
            );
        }
        parts.concat() + &queries
    }

    /// The layout of group [`FIELD_GROUP`].
    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.group_layout
    }

    /// Group [`FIELD_GROUP`] with `header` as the visibility's header.
    pub fn bind_group(&self, ctx: &GpuContext, header: &[u8]) -> wgpu::BindGroup {
        let header = ctx.uniform_buffer("field params", header);
        let entries = self.resources.entries(&header);
        ctx.bind_group("field group", &self.group_layout, &entries)
    }

    /// Moves the bound instances to `instances`' transforms (the same fields, instance by
    /// instance, as at [`Self::new`]): their records are rewritten in place on the device, the
    /// fields stay where they are; with the top level, its tree is rebuilt on the host over the
    /// moved spheres and rewritten too. What a moving rigid object costs the field kernels per
    /// frame. Waits until the device holds them, so the upload is this call's cost.
    ///
    /// Errors: [`GpuError::Invalid`] for another instance count or another field at an index;
    /// [`GpuError::Poll`] if waiting for the upload fails.
    pub fn place(&self, ctx: &GpuContext, instances: &[FieldInstance]) -> Result<(), GpuError> {
        if instances.len() != self.records.len() {
            return Err(GpuError::Invalid(format!(
                "{} instances placed on {} bound",
                instances.len(),
                self.records.len()
            )));
        }
        let mut records = self.records.clone();
        for (i, (r, inst)) in records.iter_mut().zip(instances).enumerate() {
            if !Arc::ptr_eq(&inst.field, &self.instance_fields[i]) {
                return Err(GpuError::Invalid(format!(
                    "instance {i} placed with another field than the one bound"
                )));
            }
            *r = placed(inst, *r);
        }
        ctx.queue
            .write_buffer(&self.resources.instances, 0, bytemuck::cast_slice(&records));
        if let Some(top) = self
            .resources
            .top
            .as_ref()
            .filter(|_| !instances.is_empty())
        {
            ctx.queue
                .write_buffer(top, 0, bytemuck::cast_slice(&sphere_nodes(instances)));
        }
        ctx.queue.submit([]);
        ctx.wait("waiting for the instances' upload")
    }

    /// Field instances bound.
    pub fn instance_count(&self) -> u32 {
        self.records.len() as u32
    }

    /// Bytes of stored distances on the device.
    pub fn field_bytes(&self) -> u64 {
        self.field_bytes
    }

    /// Storage windows the fields occupy (storage layout), `None` for the texture layout.
    pub fn storage_windows(&self) -> Option<usize> {
        match &self.resources.store {
            FieldStore::Windows { buffers, .. } => Some(buffers.len()),
            FieldStore::Texture { .. } => None,
        }
    }

    /// Slices of the field texture (texture layout), `None` for the storage layout.
    pub fn texture_depth(&self) -> Option<u32> {
        match &self.resources.store {
            FieldStore::Windows { .. } => None,
            FieldStore::Texture { texture, .. } => Some(texture.depth()),
        }
    }
}

/// The stored words in windows of at most the binding limit (and `opts.window_bytes`).
fn upload_windows(
    ctx: &GpuContext,
    packed: &mut PackedFields,
    opts: &FieldBindingOptions,
) -> Result<(FieldStore, u64), GpuError> {
    let (words, bases) = field_words(&packed.fields);
    packed.set_data_base(&bases);
    let max_binding = ctx.max_binding();
    let window_bytes = opts.window_bytes.unwrap_or(max_binding).min(max_binding);
    let window_words = ((window_bytes / 4) / 64 * 64).max(64) as usize;
    let windows_needed = words.len().div_ceil(window_words).max(1);
    let max_windows = ctx
        .limits()
        .max_storage_buffers_per_shader_stage
        .saturating_sub(opts.kernel_storage_buffers + TABLE_BUFFERS) as usize;
    if windows_needed > max_windows {
        return Err(GpuError::TooLarge {
            what: format!("fields in {windows_needed} storage windows"),
            need: words.len() as u64 * 4,
            limit: max_windows as u64 * window_words as u64 * 4,
            limit_name: "max_storage_buffer_binding_size × free storage bindings",
        });
    }
    let buffers = (0..windows_needed)
        .map(|w| {
            let lo = (w * window_words).min(words.len());
            let hi = ((w + 1) * window_words).min(words.len());
            ctx.storage_buffer("field window", bytemuck::cast_slice(&words[lo..hi]))
        })
        .collect();
    let store = FieldStore::Windows {
        buffers,
        window_words,
    };
    Ok((store, words.len() as u64 * 4))
}

/// The maps as tiles of one 3D texture; the instances learn their tiles.
fn upload_texture(
    ctx: &GpuContext,
    packed: &mut PackedFields,
    opts: &FieldBindingOptions,
) -> Result<(FieldStore, u64), GpuError> {
    let texture = FieldTexture::new(ctx, &packed.fields, opts.max_texture_depth)?;
    packed.set_data_base(texture.first_tiles());
    for (inst, &fi) in packed.instances.iter_mut().zip(&packed.field_of_instance) {
        let (tiles_per_row, tiles_per_slice) = texture.tiles(fi);
        let (tile_width, tile_height) = texture.tile_shape(fi);
        inst.tiles_per_row = tiles_per_row;
        inst.tiles_per_slice = tiles_per_slice;
        inst.tile_width = tile_width;
        inst.tile_height = tile_height;
    }
    let bytes = texture.bytes();
    let view = texture.view();
    let texture = Box::new(texture);
    Ok((FieldStore::Texture { texture, view }, bytes))
}

/// The declarations of the field group's tables, mesh and instances.
fn group_prelude() -> String {
    format!(
        "// Field group (src/gpu/field_binding.rs): sphere points and 1-bit means, sphere\n\
         // triangulations, placed fields.\n\
         @group({FIELD_GROUP}) @binding(1) var<storage, read> tables: array<vec4<f32>>;\n\
         @group({FIELD_GROUP}) @binding(2) var<storage, read> mesh: array<vec4<u32>>;\n\
         @group({FIELD_GROUP}) @binding(3) var<storage, read> instances: array<Instance>;\n"
    )
}

/// `FIXED_SPHERE`, `FIXED_LAYOUT` and `FIXED_PRECISION`: the code every instance shares, or
/// `VARIES` (WGSL `fixed_or`). With them the shader compiler drops the branches of the other
/// kinds; llvmpipe would otherwise run every branch of a lookup, masked, for every ray.
/// `OWNER_TABLES` and `TEXEL_TABLES`: whether any instance has that table (without, the
/// compiler drops the table reads and the lookup is the ring search and the layout's map).
/// `SINGLE_INSTANCE`: one instance is bound (kernels drop their loops over the others).
fn kinds_prelude(instances: &[FieldInstanceGpu]) -> String {
    let shared = |f: fn(&FieldInstanceGpu) -> u32| -> u32 {
        match instances.first().map(f) {
            Some(v) if instances.iter().all(|i| f(i) == v) => v,
            _ => u32::MAX,
        }
    };
    format!(
        "const VARIES: u32 = 0xffffffffu;\n\
         const FIXED_SPHERE: u32 = {}u;\n\
         const FIXED_LAYOUT: u32 = {}u;\n\
         const FIXED_PRECISION: u32 = {}u;\n\
         const OWNER_TABLES: bool = {};\n\
         const TEXEL_TABLES: bool = {};\n\
         const SINGLE_INSTANCE: bool = {};\n\
         // `fixed` where every instance shares it, else the instance's own `value`.\n\
         fn fixed_or(fixed: u32, value: u32) -> u32 {{ return select(fixed, value, fixed == VARIES); }}\n",
        shared(|i| i.sphere_kind),
        shared(|i| i.layout_kind),
        shared(|i| i.storage_precision),
        instances.iter().any(|i| i.owner_grid > 0),
        instances.iter().any(|i| i.texel_grid > 0),
        instances.len() == 1,
    )
}

/// `WINDOW_WORDS`, the window bindings and `load_word` for `n` windows.
fn window_prelude(n: usize, window_words: usize) -> String {
    let mut s = format!("const WINDOW_WORDS: u32 = {window_words}u;\n");
    for i in 0..n {
        s += &format!(
            "@group({FIELD_GROUP}) @binding({}) var<storage, read> win{i}: array<u32>;\n",
            FIRST_STORE_BINDING as usize + i
        );
    }
    s += "fn load_word(address: u32) -> u32 {\n    let i = address % WINDOW_WORDS;\n    switch address / WINDOW_WORDS {\n";
    for i in 0..n {
        s += &format!("        case {i}u: {{ return win{i}[i]; }}\n");
    }
    s += "        default: { return 0u; }\n    }\n}\n";
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_prelude_declares_every_window_once() {
        let s = group_prelude() + &window_prelude(3, 1024);
        assert!(s.contains("const WINDOW_WORDS: u32 = 1024u;"));
        for b in (1..=TABLE_BUFFERS).chain(FIRST_STORE_BINDING..FIRST_STORE_BINDING + 3) {
            let decl = format!("@group({FIELD_GROUP}) @binding({b})");
            assert_eq!(s.matches(&decl).count(), 1, "binding {b}");
        }
        for i in 0..3 {
            assert!(s.contains(&format!("case {i}u: {{ return win{i}[i]; }}")));
        }
        assert!(!s.contains("win3"));
    }
}
