//! The GPU renderer: one wgpu compute dispatch of `gpu.wgsl` (headless, no surface), storage
//! buffers for the spectra, maps and objects, the linear RGB image read back.

use super::prepare::Prepared;
use super::Image;
use crate::error::{Error, Result};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use wgpu::util::DeviceExt;

/// The most groups of four coefficients a texel may hold on the GPU (`MAX_GROUPS` in the shader):
/// 32 spectra, [`crate::envmap::convert::own_basis::MAX_K`].
pub const MAX_GROUPS: usize = 8;

/// The shader, next to the host code that drives it.
pub const SHADER: &str = include_str!("gpu.wgsl");

/// A device with the renderer's pipeline, created once and reused for many frames.
pub struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline: wgpu::ComputePipeline,
    info: wgpu::AdapterInfo,
    limits: wgpu::Limits,
    errors: Arc<Mutex<Vec<String>>>,
}

/// What the adapter is, for reports.
#[derive(Debug, Clone, serde::Serialize)]
pub struct AdapterReport {
    /// The adapter's name as wgpu reports it (e.g. the GPU's model).
    pub name: String,
    /// The graphics API, lowercase (`vulkan`, `metal`, `dx12`, `gl`).
    pub backend: String,
    /// wgpu's device type (`DiscreteGpu`, `IntegratedGpu`, `Cpu`, ...).
    pub device_type: String,
    /// The driver's name and version info, space-separated (may be empty).
    pub driver: String,
}

/// Where the time of one GPU frame went, in seconds.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct GpuTiming {
    /// Creating and filling the buffers.
    pub upload_s: f64,
    /// The compute dispatch, from submit until the device is idle.
    pub compute_s: f64,
    /// Copying the image back and mapping it.
    pub readback_s: f64,
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gpu")
            .field("adapter", &self.info.name)
            .finish()
    }
}

impl Gpu {
    /// Finds an adapter (any backend wgpu was built with; `WGPU_BACKEND` and
    /// `WGPU_ADAPTER_NAME` are honoured), opens a device and compiles the shader. An error, never
    /// a panic, when there is no adapter or the shader does not compile.
    pub fn new() -> Result<Gpu> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        }))
        .map_err(|e| {
            Error::invalid(format!(
                "no GPU adapter found ({e}); install a Vulkan driver (e.g. Mesa's lavapipe, \
                 package mesa-vulkan-drivers) or use the CPU backend"
            ))
        })?;
        let info = adapter.get_info();
        let alimits = adapter.limits();
        let mut limits = wgpu::Limits::downlevel_defaults();
        // Seven read-only buffers and the output (WebGPU's default limit).
        limits.max_storage_buffers_per_shader_stage = 8;
        limits.max_storage_buffer_binding_size = alimits.max_storage_buffer_binding_size;
        limits.max_buffer_size = alimits.max_buffer_size;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("specmap render"),
            required_features: wgpu::Features::empty(),
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| {
            Error::invalid(format!(
                "the GPU adapter {} could not open a device: {e}",
                info.name
            ))
        })?;
        let errors: Arc<Mutex<Vec<String>>> = Arc::default();
        {
            let errors = errors.clone();
            device.on_uncaptured_error(Arc::new(move |e| {
                if let Ok(mut v) = errors.lock() {
                    v.push(e.to_string());
                }
            }));
        }
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("render.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("render"),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::invalid(format!(
                "the render shader failed on {}: {e}",
                info.name
            )));
        }
        Ok(Gpu {
            device,
            queue,
            pipeline,
            info,
            limits,
            errors,
        })
    }

    /// What the adapter this renderer runs on is.
    pub fn adapter(&self) -> AdapterReport {
        AdapterReport {
            name: self.info.name.clone(),
            backend: format!("{:?}", self.info.backend).to_lowercase(),
            device_type: format!("{:?}", self.info.device_type),
            driver: format!("{} {}", self.info.driver, self.info.driver_info)
                .trim()
                .to_string(),
        }
    }

    /// Whether the adapter is a CPU (software) implementation such as lavapipe.
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    fn storage(&self, label: &str, bytes: &[u8]) -> Result<wgpu::Buffer> {
        // Bindings cannot be empty: pad with zeros.
        let mut padded;
        let contents = if bytes.len() < 16 {
            padded = bytes.to_vec();
            padded.resize(16, 0);
            &padded[..]
        } else {
            bytes
        };
        if contents.len() as u64 > self.limits.max_storage_buffer_binding_size {
            return Err(Error::invalid(format!(
                "{label}: {} bytes exceed the adapter's storage buffer limit of {} bytes",
                contents.len(),
                self.limits.max_storage_buffer_binding_size
            )));
        }
        Ok(self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            }))
    }

    /// Renders the prepared scene: checked against the adapter's limits, uploaded, dispatched
    /// and read back, each stage timed.
    ///
    /// ```no_run
    /// use specmap::render::{gpu::Gpu, prepare::Prepared, Preset, Spectral};
    ///
    /// let scene = Preset::Cylinders.scene(512, 512, "D65", None)?;
    /// let prepared = Prepared::new(&scene, &Spectral::default())?;
    /// let gpu = Gpu::new()?; // once, for many frames
    /// let (image, timing) = gpu.render(&prepared)?;
    /// println!("{}x{} in {:.3} s", image.width, image.height, timing.compute_s);
    /// # Ok::<(), specmap::error::Error>(())
    /// ```
    pub fn render(&self, p: &Prepared) -> Result<(Image, GpuTiming)> {
        let t0 = Instant::now();
        let (w, h) = (p.params.width as usize, p.params.height as usize);
        let out_bytes = self.check_frame(p)?;
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let frame = self.upload(p, out_bytes)?;
        self.poll()?;
        let t1 = Instant::now();
        self.dispatch(&frame.bind, w, h);
        self.poll()?;
        let t2 = Instant::now();
        let mapped = self.copy_back(&frame, out_bytes);
        self.poll()?;
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::invalid(format!("GPU render failed: {e}")));
        }
        if let Some(e) = self.errors.lock().ok().and_then(|mut v| v.pop()) {
            return Err(Error::invalid(format!("GPU render failed: {e}")));
        }
        let pixels = read_mapped(&frame.staging, mapped)?;
        let t3 = Instant::now();
        Ok((
            Image {
                width: w,
                height: h,
                pixels,
            },
            GpuTiming {
                upload_s: (t1 - t0).as_secs_f64(),
                compute_s: (t2 - t1).as_secs_f64(),
                readback_s: (t3 - t2).as_secs_f64(),
            },
        ))
    }

    /// The image's size in bytes (four f32 a pixel): an error where it or a lighting's spectra
    /// exceed what the adapter or the shader holds.
    fn check_frame(&self, p: &Prepared) -> Result<u64> {
        let (w, h) = (p.params.width as usize, p.params.height as usize);
        let out_bytes = (w * h * 16) as u64;
        if out_bytes > self.limits.max_storage_buffer_binding_size {
            return Err(Error::invalid(format!(
                "a {w}x{h} image needs {out_bytes} bytes, above the adapter's storage buffer \
                 limit of {} bytes; render a smaller image",
                self.limits.max_storage_buffer_binding_size
            )));
        }
        if let Some(l) = p
            .lightings
            .iter()
            .find(|l| l.layout[0] as usize > MAX_GROUPS)
        {
            return Err(Error::invalid(format!(
                "a lighting of {} spectra: the GPU renderer expands at most {} (the CPU \
                 renderer has no limit)",
                4 * l.layout[0],
                4 * MAX_GROUPS
            )));
        }
        Ok(out_bytes)
    }

    /// The prepared arrays as buffers, the output and its staging buffer, bound as the shader
    /// declares.
    fn upload(&self, p: &Prepared, out_bytes: u64) -> Result<Frame> {
        let params = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("params"),
                contents: bytemuck::bytes_of(&p.params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let spectra = self.storage("spectra", bytemuck::cast_slice(&p.spectra))?;
        let objects = self.storage("objects", bytemuck::cast_slice(&p.objects))?;
        let materials = self.storage("materials", bytemuck::cast_slice(&p.materials))?;
        let lightings = self.storage("lightings", bytemuck::cast_slice(&p.lightings))?;
        let maps = self.storage("maps", bytemuck::cast_slice(&p.maps))?;
        let texels = self.storage("texels", bytemuck::cast_slice(&p.texels))?;
        let rows = self.storage("rows", bytemuck::cast_slice(&p.rows))?;
        let out = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("out"),
            size: out_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("staging"),
            size: out_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // Binding i of the shader, in its order.
        let bound = [
            params, spectra, objects, materials, lightings, maps, texels, out, rows,
        ];
        let layout = self.pipeline.get_bind_group_layout(0);
        let entries: Vec<wgpu::BindGroupEntry> = bound
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("render"),
            layout: &layout,
            entries: &entries,
        });
        Ok(Frame {
            bind,
            bound,
            staging,
        })
    }

    /// One invocation per pixel, in workgroups of 8 x 8.
    fn dispatch(&self, bind: &wgpu::BindGroup, w: usize, h: usize) {
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups((w as u32).div_ceil(8), (h as u32).div_ceil(8), 1);
        }
        self.queue.submit([enc.finish()]);
    }

    /// Copies the output to the staging buffer and asks for it mapped: what the mapping
    /// answers once the device is polled.
    fn copy_back(&self, frame: &Frame, out_bytes: u64) -> Mapped {
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        enc.copy_buffer_to_buffer(frame.out(), 0, &frame.staging, 0, out_bytes);
        self.queue.submit([enc.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        frame
            .staging
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |r| {
                let _ = tx.send(r);
            });
        rx
    }

    fn poll(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| Error::invalid(format!("waiting for the GPU: {e}")))
    }
}

/// A frame's buffers on the device: bound in the shader's order (the output among them), and
/// the staging buffer the output is read back through.
struct Frame {
    bind: wgpu::BindGroup,
    bound: [wgpu::Buffer; 9],
    staging: wgpu::Buffer,
}

impl Frame {
    /// The output image (binding 7).
    fn out(&self) -> &wgpu::Buffer {
        &self.bound[7]
    }
}

/// What mapping the staging buffer answers.
type Mapped = std::sync::mpsc::Receiver<std::result::Result<(), wgpu::BufferAsyncError>>;

/// The linear RGB pixels of the mapped staging buffer (four f32 a pixel, the fourth unused).
fn read_mapped(staging: &wgpu::Buffer, mapped: Mapped) -> Result<Vec<[f32; 3]>> {
    mapped
        .recv()
        .map_err(|_| Error::invalid("GPU readback was cancelled"))?
        .map_err(|e| Error::invalid(format!("GPU readback failed: {e}")))?;
    let pixels: Vec<[f32; 3]> = {
        let data = staging
            .slice(..)
            .get_mapped_range()
            .map_err(|e| Error::invalid(format!("GPU readback failed: {e}")))?;
        let v: &[[f32; 4]] = bytemuck::cast_slice(&data);
        v.iter().map(|p| [p[0], p[1], p[2]]).collect()
    };
    staging.unmap();
    Ok(pixels)
}

#[cfg(test)]
mod tests {
    /// The shader parses and validates without an adapter (a GPU-less machine still checks it).
    #[test]
    fn the_shader_is_valid_wgsl() {
        let module = naga::front::wgsl::parse_str(super::SHADER)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(super::SHADER)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(super::SHADER)));
    }
}
