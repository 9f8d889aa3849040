//! Compute and graphics pipelines and dynamic rendering. Their sets come
//! from `descriptors.rs`.

use super::pipeline_create::{create_graphics, create_with_stages, pipeline_key};
use super::pipeline_store::{GraphicsPipelineDesc, SharedPipeline, Specialization, Stages};
use super::{Buffer, Context, DescriptorSet, DescriptorSetLayout, VkResult};
use ash::vk;
use std::sync::Arc;

fn bind_sets(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    point: vk::PipelineBindPoint,
    layout: vk::PipelineLayout,
    sets: &[&DescriptorSet],
) {
    let raw: Vec<_> = sets.iter().map(|s| s.raw).collect();
    let serial = ctx.frame_serial.load(std::sync::atomic::Ordering::Relaxed);
    for set in sets {
        set.bound_in.set(serial);
    }
    unsafe {
        ctx.device
            .cmd_bind_descriptor_sets(cmd, point, layout, 0, &raw, &[])
    };
}

fn push(ctx: &Context, cmd: vk::CommandBuffer, layout: vk::PipelineLayout, data: &[u8]) {
    if !data.is_empty() {
        unsafe {
            ctx.device
                .cmd_push_constants(cmd, layout, vk::ShaderStageFlags::ALL, 0, data)
        };
    }
}

/// Workgroups of 8x8 invocations covering a `width` x `height` grid (the
/// local size of every per-pixel and per-texel compute shader here).
pub fn groups_8x8(width: u32, height: u32) -> [u32; 3] {
    [width.div_ceil(8), height.div_ceil(8), 1]
}

/// A compute pipeline; equal ones are shared through the context's
/// `PipelineStore`.
pub struct ComputePipeline {
    // Declared before `ctx`: fields drop in order, and the shared pipeline
    // must go while the device it was made on is still held.
    _shared: Arc<SharedPipeline>,
    ctx: Arc<Context>,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub name: String,
}

impl ComputePipeline {
    /// `shader` is a path under glsl/, e.g. "reference/trace.comp".
    pub fn new(
        ctx: &Arc<Context>,
        shader: &str,
        sets: &[&DescriptorSetLayout],
        push_size: u32,
    ) -> VkResult<Self> {
        Self::specialized(ctx, shader, &Specialization::new(), sets, push_size)
    }

    /// As `new`, with specialisation constants.
    pub fn specialized(
        ctx: &Arc<Context>,
        shader: &str,
        specialization: &Specialization,
        sets: &[&DescriptorSetLayout],
        push_size: u32,
    ) -> VkResult<Self> {
        let stages = [(vk::ShaderStageFlags::COMPUTE, shader)];
        let key = pipeline_key(
            Stages::Compute(shader.to_string()),
            specialization,
            sets,
            push_size,
        );
        let shared = ctx.pipelines().get_or_create(key, |cache| {
            let (raw, layout) = create_with_stages(
                ctx,
                &stages,
                specialization,
                sets,
                push_size,
                |infos, layout| {
                    let info = vk::ComputePipelineCreateInfo::default()
                        .stage(infos[0])
                        .layout(layout);
                    unsafe { ctx.device.create_compute_pipelines(cache, &[info], None) }
                },
            )?;
            ctx.set_name(raw, shader);
            Ok((raw, layout))
        })?;
        Ok(Self {
            raw: shared.raw,
            layout: shared.layout,
            _shared: shared,
            ctx: ctx.clone(),
            name: shader.to_string(),
        })
    }

    /// Binds the pipeline and sets, pushes constants and dispatches `groups`
    /// (`Commands::dispatch`).
    pub(super) fn dispatch(
        &self,
        cmd: vk::CommandBuffer,
        sets: &[&DescriptorSet],
        push_data: &[u8],
        groups: [u32; 3],
    ) {
        let ctx = &self.ctx;
        unsafe {
            ctx.device
                .cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.raw)
        };
        bind_sets(ctx, cmd, vk::PipelineBindPoint::COMPUTE, self.layout, sets);
        push(ctx, cmd, self.layout, push_data);
        unsafe {
            ctx.device
                .cmd_dispatch(cmd, groups[0], groups[1], groups[2])
        };
    }

    /// Binds the pipeline and sets, pushes constants and dispatches the
    /// `VkDispatchIndirectCommand` at byte `offset` of `args` (a
    /// `StorageIndirect` buffer the caller has barriered to `IndirectRead`).
    pub(super) fn dispatch_indirect(
        &self,
        cmd: vk::CommandBuffer,
        sets: &[&DescriptorSet],
        push_data: &[u8],
        args: &Buffer,
        offset: u64,
    ) {
        let ctx = &self.ctx;
        unsafe {
            ctx.device
                .cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.raw)
        };
        bind_sets(ctx, cmd, vk::PipelineBindPoint::COMPUTE, self.layout, sets);
        push(ctx, cmd, self.layout, push_data);
        unsafe { ctx.device.cmd_dispatch_indirect(cmd, args.raw, offset) };
    }
}

/// A graphics pipeline; equal ones are shared through the context's
/// `PipelineStore`.
pub struct GraphicsPipeline {
    // Before `ctx`, as in `ComputePipeline`.
    _shared: Arc<SharedPipeline>,
    ctx: Arc<Context>,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
}

impl GraphicsPipeline {
    /// Shader paths are `'static` (they name SPIR-V embedded at build
    /// time), so the description itself serves as the store's key.
    pub fn new(
        ctx: &Arc<Context>,
        desc: &GraphicsPipelineDesc<'static>,
        sets: &[&DescriptorSetLayout],
    ) -> VkResult<Self> {
        let mut stages = vec![(vk::ShaderStageFlags::VERTEX, desc.vertex)];
        if let Some(g) = desc.geometry {
            stages.push((vk::ShaderStageFlags::GEOMETRY, g));
        }
        stages.push((vk::ShaderStageFlags::FRAGMENT, desc.fragment));
        let key = pipeline_key(
            Stages::Graphics(desc.clone()),
            &desc.specialization,
            sets,
            desc.push_size,
        );
        let shared = ctx.pipelines().get_or_create(key, |cache| {
            let (raw, layout) = create_with_stages(
                ctx,
                &stages,
                &desc.specialization,
                sets,
                desc.push_size,
                |infos, layout| create_graphics(ctx, desc, infos, layout, cache),
            )?;
            ctx.set_name(raw, desc.fragment);
            Ok((raw, layout))
        })?;
        Ok(Self {
            raw: shared.raw,
            layout: shared.layout,
            _shared: shared,
            ctx: ctx.clone(),
        })
    }

    /// Binds the pipeline, its sets and push constants, and sets a full
    /// viewport and scissor (`Rendering::bind`).
    pub(super) fn bind(
        &self,
        cmd: vk::CommandBuffer,
        sets: &[&DescriptorSet],
        push_data: &[u8],
        extent: vk::Extent2D,
    ) {
        let ctx = &self.ctx;
        unsafe {
            ctx.device
                .cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.raw);
            let viewport = vk::Viewport {
                x: 0.0,
                y: 0.0,
                width: extent.width as f32,
                height: extent.height as f32,
                min_depth: 0.0,
                max_depth: 1.0,
            };
            ctx.device.cmd_set_viewport(cmd, 0, &[viewport]);
            ctx.device.cmd_set_scissor(
                cmd,
                0,
                &[vk::Rect2D {
                    offset: vk::Offset2D::default(),
                    extent,
                }],
            );
        }
        bind_sets(ctx, cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, sets);
        push(ctx, cmd, self.layout, push_data);
    }
}
