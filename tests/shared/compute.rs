//! A compute shader run outside the renderer, once, by the GPU tests of library functions and the GPU rays bench:
//! its pipeline from a composed module, one thread per element, and a buffer read back.

use std::borrow::Cow;
use wgpu::util::DeviceExt;

/// The binding of a one-off shader's input (read only) and of its results: past every binding the libraries
/// declare.
pub const INPUT_BINDING: u32 = 100;
pub const OUTPUT_BINDING: u32 = 101;

/// A one-off shader's own buffers: its input, and room for `output_bytes` of results to read back.
pub struct Io {
    pub input: wgpu::Buffer,
    pub output: wgpu::Buffer,
    pub output_bytes: u64,
}

impl Io {
    pub fn new(device: &wgpu::Device, label: &str, input: &[u8], output_bytes: u64) -> Io {
        let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&format!("{label}_input")),
            contents: input,
            usage: wgpu::BufferUsages::STORAGE,
        });
        let output = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("{label}_output")),
            size: output_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Io { input, output, output_bytes }
    }

    /// The bind group of `layout`: `others` (a world's bindings, or none) and these two buffers.
    pub fn bind_group<'a>(
        &'a self,
        device: &wgpu::Device,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        mut others: Vec<wgpu::BindGroupEntry<'a>>,
    ) -> wgpu::BindGroup {
        others.push(wgpu::BindGroupEntry { binding: INPUT_BINDING, resource: self.input.as_entire_binding() });
        others.push(wgpu::BindGroupEntry { binding: OUTPUT_BINDING, resource: self.output.as_entire_binding() });
        device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &others })
    }
}

/// The pipeline of `module`'s `main`; with `layout` `None`, wgpu derives one from the bindings `main` uses.
pub fn pipeline(
    device: &wgpu::Device,
    label: &str,
    module: naga::Module,
    layout: Option<&wgpu::BindGroupLayout>,
) -> wgpu::ComputePipeline {
    let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Naga(Cow::Owned(module)),
    });
    let pipeline_layout = layout.map(|layout| {
        device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(layout)],
            immediate_size: 0,
        })
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: pipeline_layout.as_ref(),
        module: &shader,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// Records one dispatch of `pipeline` over `threads` threads in workgroups of 64.
pub fn record_dispatch(
    encoder: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    bind_group: &wgpu::BindGroup,
    threads: u32,
) {
    let mut pass = encoder.begin_compute_pass(&Default::default());
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    pass.dispatch_workgroups(threads.div_ceil(64), 1, 1);
}

/// Runs `pipeline` over `threads` threads, then returns `io`'s results. (The GPU tests' way; the rays bench times
/// its dispatch alone.)
#[allow(dead_code)]
pub fn run_and_read(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    pipeline: &wgpu::ComputePipeline,
    bind_group: &wgpu::BindGroup,
    threads: u32,
    io: &Io,
) -> Vec<u8> {
    let mut encoder = device.create_command_encoder(&Default::default());
    record_dispatch(&mut encoder, pipeline, bind_group, threads);
    queue.submit([encoder.finish()]);
    read_buffer(device, queue, &io.output, io.output_bytes)
}

/// The first `bytes` of `buffer` (a `COPY_SRC` buffer), once the GPU has finished everything submitted.
pub fn read_buffer(device: &wgpu::Device, queue: &wgpu::Queue, buffer: &wgpu::Buffer, bytes: u64) -> Vec<u8> {
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &readback, 0, bytes);
    queue.submit([encoder.finish()]);
    readback.slice(..).map_async(wgpu::MapMode::Read, |mapped| mapped.expect("readback maps"));
    device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None }).expect("the GPU finishes");
    let out = readback.slice(..).get_mapped_range().to_vec();
    readback.unmap();
    out
}
