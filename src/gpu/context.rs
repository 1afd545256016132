//! The headless wgpu device: adapter choice, limits, features, and the buffer helpers every
//! kernel uses (upload, read-back, timestamp queries).

use super::loop_budget::{add_kernel, Dispatched};
use super::GpuError;
use std::time::Duration;
use wgpu::util::DeviceExt;

/// Environment variable that forces an adapter: `lavapipe`, `hardware`, or a substring of the
/// adapter name (case-insensitive). Unset or `auto`: hardware where there is one, else lavapipe.
pub const ADAPTER_ENV: &str = "VISFIELD_ADAPTER";

/// Which Vulkan adapter to use.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum AdapterPreference {
    /// A hardware adapter (discrete, then integrated, then virtual) where there is one, else a
    /// CPU adapter (lavapipe).
    Auto,
    /// A CPU adapter (Mesa lavapipe / llvmpipe); an error when there is none.
    Lavapipe,
    /// A non-CPU adapter; an error when there is none.
    Hardware,
    /// The first adapter whose name contains this (case-insensitive).
    Name(String),
}

impl AdapterPreference {
    /// Parses `auto`, `lavapipe` (also `llvmpipe`, `cpu`), `hardware` (also `gpu`), or any
    /// other text as a name substring.
    pub fn parse(s: &str) -> AdapterPreference {
        match s.trim().to_ascii_lowercase().as_str() {
            "" | "auto" => AdapterPreference::Auto,
            "lavapipe" | "llvmpipe" | "cpu" => AdapterPreference::Lavapipe,
            "hardware" | "gpu" => AdapterPreference::Hardware,
            _ => AdapterPreference::Name(s.trim().to_string()),
        }
    }

    /// The preference named by [`ADAPTER_ENV`], or [`AdapterPreference::Auto`] when unset.
    pub fn from_env() -> AdapterPreference {
        std::env::var(ADAPTER_ENV)
            .map(|s| AdapterPreference::parse(&s))
            .unwrap_or(AdapterPreference::Auto)
    }
}

impl std::str::FromStr for AdapterPreference {
    type Err = std::convert::Infallible;

    /// [`AdapterPreference::parse`], for command-line flags.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(AdapterPreference::parse(s))
    }
}

/// Rank of a device type for [`AdapterPreference::Auto`] (lower is preferred).
fn hardware_rank(t: wgpu::DeviceType) -> u32 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

fn is_cpu(info: &wgpu::AdapterInfo) -> bool {
    info.device_type == wgpu::DeviceType::Cpu || info.name.to_ascii_lowercase().contains("llvmpipe")
}

/// A headless wgpu device on the Vulkan backend, created with the adapter's own limits (so
/// that kernels can size their bindings from [`GpuContext::limits`]) and with timestamp queries
/// where the adapter has them.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    limits: wgpu::Limits,
    timestamps: bool,
    /// Whether the device was opened with hardware ray queries (wgpu's
    /// `EXPERIMENTAL_RAY_QUERY`), where the adapter offers them.
    ray_query: bool,
}

impl GpuContext {
    /// Opens the adapter `pref` selects.
    ///
    /// Errors: [`GpuError::NoAdapter`] when the Vulkan backend lists no adapter at all (no
    /// driver installed), [`GpuError::AdapterNotFound`] when adapters exist but none matches.
    pub fn new(pref: AdapterPreference) -> Result<GpuContext, GpuError> {
        pollster::block_on(Self::new_async(pref))
    }

    async fn new_async(pref: AdapterPreference) -> Result<GpuContext, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let adapters = instance.enumerate_adapters(wgpu::Backends::VULKAN).await;
        if adapters.is_empty() {
            return Err(GpuError::NoAdapter);
        }
        let names: Vec<String> = adapters
            .iter()
            .map(|a| {
                let i = a.get_info();
                format!("{} ({:?})", i.name, i.device_type)
            })
            .collect();
        let chosen = match &pref {
            AdapterPreference::Auto => adapters
                .into_iter()
                .min_by_key(|a| hardware_rank(a.get_info().device_type)),
            AdapterPreference::Lavapipe => adapters.into_iter().find(|a| is_cpu(&a.get_info())),
            AdapterPreference::Hardware => adapters
                .into_iter()
                .filter(|a| !is_cpu(&a.get_info()))
                .min_by_key(|a| hardware_rank(a.get_info().device_type)),
            AdapterPreference::Name(n) => {
                let n = n.to_ascii_lowercase();
                adapters
                    .into_iter()
                    .find(|a| a.get_info().name.to_ascii_lowercase().contains(&n))
            }
        };
        let adapter = chosen.ok_or_else(|| GpuError::AdapterNotFound {
            requested: format!("{pref:?}"),
            available: names.join(", "),
        })?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let mut required_features = if timestamps {
            wgpu::Features::TIMESTAMP_QUERY
        } else {
            wgpu::Features::empty()
        };
        // Ray queries (src/gpu/ray_query.rs) where the adapter offers them: wgpu marks them
        // experimental, so the device is opened with its experimental features allowed (the
        // adapter's own limits, above, are what permit acceleration structures at all).
        let ray_query = adapter
            .features()
            .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY);
        if ray_query {
            required_features |= wgpu::Features::EXPERIMENTAL_RAY_QUERY;
        }
        // SAFETY: the experimental feature is ray queries; its known pitfalls (docs/gpu.md,
        // "Ray queries") are avoided by the only WGSL that uses it, shaders/ray_query.wgsl.
        let experimental_features = if ray_query {
            unsafe { wgpu::ExperimentalFeatures::enabled() }
        } else {
            wgpu::ExperimentalFeatures::disabled()
        };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("visfield"),
                required_features,
                required_limits: limits.clone(),
                experimental_features,
                ..Default::default()
            })
            .await
            .map_err(|source| GpuError::RequestDevice {
                what: format!("opening a device on adapter {:?}", info.name),
                source,
            })?;
        Ok(GpuContext {
            device,
            queue,
            info,
            limits,
            timestamps,
            ray_query,
        })
    }

    /// Whether the device has hardware ray queries ([`super::RayQueryScene`]): the adapter
    /// offers wgpu's `EXPERIMENTAL_RAY_QUERY` (Mesa's lavapipe from 24.1, GPUs with
    /// ray-tracing units), or why not.
    pub fn ray_query_support(&self) -> Result<(), String> {
        if self.ray_query {
            Ok(())
        } else {
            Err(format!(
                "adapter {:?} ({} {}) offers no ray queries (wgpu EXPERIMENTAL_RAY_QUERY: Mesa's \
                 lavapipe before 24.1, GPUs without ray-tracing units)",
                self.info.name, self.info.driver, self.info.driver_info
            ))
        }
    }

    /// "name | driver driver_info | backend": what every result row records.
    pub fn adapter_label(&self) -> String {
        format!(
            "{} | {} {} | {:?}",
            self.info.name, self.info.driver, self.info.driver_info, self.info.backend
        )
    }

    /// The adapter name with anything but letters, digits, `-` and `_` replaced by `_`, for
    /// benchmark and file names.
    pub fn info_short(&self) -> String {
        self.info
            .name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect()
    }

    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// The device's limits (the adapter's best).
    pub fn limits(&self) -> &wgpu::Limits {
        &self.limits
    }

    /// Whether GPU timestamps are recorded.
    pub fn has_timestamps(&self) -> bool {
        self.timestamps
    }

    /// A storage buffer initialised with `data`; empty inputs get 256 zero bytes, since
    /// bindings must hold at least one element of their array.
    pub(crate) fn storage_buffer(&self, label: &str, data: &[u8]) -> wgpu::Buffer {
        let zero = [0u8; 256];
        let contents = if data.is_empty() { &zero[..] } else { data };
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            })
    }

    /// A uniform buffer initialised with `data`.
    pub(crate) fn uniform_buffer(&self, label: &str, data: &[u8]) -> wgpu::Buffer {
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: data,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            })
    }

    /// A storage buffer of `size` bytes the kernel writes and the host reads back.
    pub(crate) fn output_buffer(&self, label: &str, size: u64) -> wgpu::Buffer {
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        self.buffer(label, size.max(16), usage)
    }

    /// A bind-group layout of `entries`.
    pub(crate) fn group_layout(
        &self,
        label: &str,
        entries: &[wgpu::BindGroupLayoutEntry],
    ) -> wgpu::BindGroupLayout {
        let label = Some(label);
        (self.device).create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label, entries })
    }

    /// A bind group of `layout` holding `entries`.
    pub(crate) fn bind_group(
        &self,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        entries: &[wgpu::BindGroupEntry],
    ) -> wgpu::BindGroup {
        let label = Some(label);
        (self.device).create_bind_group(&wgpu::BindGroupDescriptor {
            label,
            layout,
            entries,
        })
    }

    /// An unmapped buffer of `size` bytes.
    fn buffer(&self, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: false,
        })
    }

    /// Compiles a WGSL compute shader with `layout` (`None`: the layout derived from the
    /// shader), returning the validation error instead of panicking.
    pub(crate) fn compute_pipeline_with_layout(
        &self,
        label: &str,
        source: &str,
        entry: &str,
        layout: Option<&wgpu::PipelineLayout>,
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = self
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout,
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            });
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(GpuError::Shader {
                shader: label.to_string(),
                message: e.to_string(),
            }),
            None => Ok(pipeline),
        }
    }

    /// Runs one compute dispatch of `groups` workgroups (split over the y dimension when it
    /// passes the per-dimension limit: the shader linearises `gid.x + gid.y · stride`) with
    /// `bind_groups` as groups 0, 1, …, copies `output` back and returns its bytes with the
    /// kernel's GPU time where timestamps exist.
    pub(crate) fn dispatch_and_read(
        &self,
        pipeline: &wgpu::ComputePipeline,
        bind_groups: &[&wgpu::BindGroup],
        groups: u32,
        output: &wgpu::Buffer,
    ) -> Result<(Vec<u8>, Option<Duration>), GpuError> {
        let size = output.size();
        let read = wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST;
        let readback = self.buffer("readback", size, read);
        let queries = self.timestamps.then(|| {
            let set = self.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kernel time"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            });
            let resolve_usage = wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC;
            let resolve = self.buffer("timestamps", 16, resolve_usage);
            (set, resolve, self.buffer("timestamps readback", 16, read))
        });
        let (gx, gy) = split_groups(groups, self.limits.max_compute_workgroups_per_dimension);
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let timestamp_writes =
                queries
                    .as_ref()
                    .map(|(set, _, _)| wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(0),
                        end_of_pass_write_index: Some(1),
                    });
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: None,
                timestamp_writes,
            });
            pass.set_pipeline(pipeline);
            for (i, g) in bind_groups.iter().enumerate() {
                pass.set_bind_group(i as u32, *g, &[]);
            }
            if groups > 0 {
                pass.dispatch_workgroups(gx, gy, 1);
            }
        }
        encoder.copy_buffer_to_buffer(output, 0, &readback, 0, size);
        if let Some((set, resolve, read)) = &queries {
            encoder.resolve_query_set(set, 0..2, resolve, 0);
            encoder.copy_buffer_to_buffer(resolve, 0, read, 0, 16);
        }
        self.queue.submit([encoder.finish()]);
        let bytes = self.read_buffer(&readback)?;
        let kernel = match &queries {
            Some((_, _, read)) => {
                let ts: Vec<u64> = bytemuck::pod_collect_to_vec(&self.read_buffer(read)?);
                let ticks = ts[1].saturating_sub(ts[0]);
                let ns = ticks as f64 * self.queue.get_timestamp_period() as f64;
                Some(Duration::from_nanos(ns.round() as u64))
            }
            None => None,
        };
        Ok((bytes, kernel))
    }

    /// Waits until the device has run all that was submitted; `what` says what for in the
    /// error.
    pub(crate) fn wait(&self, what: &'static str) -> Result<(), GpuError> {
        let waited = self.device.poll(wgpu::PollType::wait_indefinitely());
        waited
            .map(drop)
            .map_err(|source| GpuError::Poll { what, source })
    }

    /// Maps a `MAP_READ` buffer and copies its contents out.
    fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
        let (tx, rx) = std::sync::mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.wait("waiting for a read-back buffer's mapping")?;
        rx.recv()
            .map_err(|source| GpuError::MapCallback {
                what: "mapping a read-back buffer",
                source,
            })?
            .map_err(|source| GpuError::Map {
                what: "mapping a read-back buffer",
                source,
            })?;
        let bytes = buffer
            .get_mapped_range(..)
            .map_err(|source| GpuError::MappedRange {
                what: "reading a mapped read-back buffer",
                source,
            })?
            .to_vec();
        buffer.unmap();
        Ok(bytes)
    }
}

/// Invocations per workgroup of every kernel (`@workgroup_size(64)` in `shaders/`).
pub(crate) const WORKGROUP: u32 = 64;

impl GpuContext {
    /// The largest storage binding the adapter allows.
    pub fn max_binding(&self) -> u64 {
        let l = &self.limits;
        l.max_storage_buffer_binding_size.min(l.max_buffer_size)
    }

    /// Runs `pipeline` over `items` with `threads_per_item` invocations per item, each writing
    /// `words_per_thread` words, and returns the words item-major with the kernels' GPU time
    /// and the host's upload time. Items go in batches small enough for their buffer and the
    /// output to fit one binding each; `bind(batch, stride, out)` makes a batch's bind group,
    /// `stride` being the invocations per row of the dispatch grid (the shader linearises
    /// `gid.x + gid.y · stride`) and `out` the buffer the kernel writes. `item` names an item in
    /// errors. `fixed_groups` are bound as groups 1, 2, … of every batch.
    pub(crate) fn run_batched<T: bytemuck::Pod>(
        &self,
        pipeline: &wgpu::ComputePipeline,
        fixed_groups: &[&wgpu::BindGroup],
        items: &[T],
        item: &str,
        (threads_per_item, words_per_thread): (u32, u32),
        mut bind: impl FnMut(&[T], u32, &wgpu::Buffer) -> wgpu::BindGroup,
    ) -> Result<Dispatched, GpuError> {
        let words_per_item = threads_per_item as u64 * words_per_thread as u64;
        let max_binding = self.max_binding();
        let batch = (max_binding / (4 * words_per_item))
            .min(max_binding / std::mem::size_of::<T>() as u64)
            .min(u32::MAX as u64 / threads_per_item as u64) as usize;
        if batch == 0 {
            return Err(GpuError::TooLarge {
                what: format!("the output of one {item} ({words_per_item} words)"),
                need: 4 * words_per_item,
                limit: max_binding,
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        let mut words = Vec::with_capacity(items.len() * words_per_item as usize);
        let (mut kernel, mut upload) = (None, Duration::ZERO);
        for part in items.chunks(batch) {
            let t = std::time::Instant::now();
            let groups = (part.len() as u32 * threads_per_item).div_ceil(WORKGROUP);
            let (gx, _) = split_groups(groups, self.limits.max_compute_workgroups_per_dimension);
            let out_bytes = part.len() as u64 * words_per_item * 4;
            let out = self.output_buffer("out", out_bytes);
            let bind_group = bind(part, gx * WORKGROUP, &out);
            upload += t.elapsed();
            let mut bind_groups = vec![&bind_group];
            bind_groups.extend_from_slice(fixed_groups);
            let (bytes, k) = self.dispatch_and_read(pipeline, &bind_groups, groups, &out)?;
            kernel = add_kernel(kernel, k);
            words.extend(bytemuck::pod_collect_to_vec::<u8, u32>(
                &bytes[..out_bytes as usize],
            ));
        }
        Ok((words, kernel, upload))
    }
}

/// A bind-group entry.
pub(crate) fn entry(binding: u32, resource: wgpu::BindingResource<'_>) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource }
}

/// A compute-stage layout entry.
pub(crate) fn layout_entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty,
        count: None,
    }
}

/// A compute-stage storage-buffer layout entry.
pub(crate) fn storage_layout_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    buffer_layout_entry(binding, wgpu::BufferBindingType::Storage { read_only })
}

/// A compute-stage uniform-buffer layout entry.
pub(crate) fn uniform_layout_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    buffer_layout_entry(binding, wgpu::BufferBindingType::Uniform)
}

fn buffer_layout_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    let ty = wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    layout_entry(binding, ty)
}

/// Splits `groups` workgroups into (x, y) with x ≤ `max_dim`, x·y ≥ groups.
pub(crate) fn split_groups(groups: u32, max_dim: u32) -> (u32, u32) {
    if groups <= max_dim {
        (groups, 1)
    } else {
        (max_dim, groups.div_ceil(max_dim))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adapter_preferences_parse() {
        assert_eq!(AdapterPreference::parse(""), AdapterPreference::Auto);
        assert_eq!(AdapterPreference::parse("Auto"), AdapterPreference::Auto);
        assert_eq!(
            AdapterPreference::parse("lavapipe"),
            AdapterPreference::Lavapipe
        );
        assert_eq!(
            AdapterPreference::parse(" LLVMpipe "),
            AdapterPreference::Lavapipe
        );
        assert_eq!(
            AdapterPreference::parse("hardware"),
            AdapterPreference::Hardware
        );
        assert_eq!(
            AdapterPreference::parse("NVIDIA H100"),
            AdapterPreference::Name("NVIDIA H100".into())
        );
    }

    #[test]
    fn workgroups_split_over_two_dimensions_cover_every_item() {
        assert_eq!(split_groups(0, 65535), (0, 1));
        assert_eq!(split_groups(65535, 65535), (65535, 1));
        let (x, y) = split_groups(200_000, 65535);
        assert_eq!((x, y), (65535, 4));
        assert!(x as u64 * y as u64 >= 200_000);
    }
}
