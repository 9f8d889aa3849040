//! How pipelines are created: shader modules from the embedded SPIR-V,
//! specialisation, pipeline layouts, fixed-function state, and the key the
//! `PipelineStore` shares them by. `pipeline.rs`'s `ComputePipeline` and
//! `GraphicsPipeline` call these through the store.

use super::pipeline_store::{GraphicsPipelineDesc, PipelineKey, Specialization, Stages};
use super::DescriptorSetLayout;
use super::{Context, VkResult};
use crate::shaders;
use ash::vk;
use std::ffi::CStr;

fn shader_module(ctx: &Context, name: &str) -> VkResult<vk::ShaderModule> {
    let code = shaders::spirv(name);
    let info = vk::ShaderModuleCreateInfo::default().code(&code);
    Ok(unsafe { ctx.device.create_shader_module(&info, None) }?)
}

fn pipeline_layout(
    ctx: &Context,
    sets: &[&DescriptorSetLayout],
    push_size: u32,
) -> VkResult<vk::PipelineLayout> {
    let raw_sets: Vec<_> = sets.iter().map(|s| s.raw).collect();
    let ranges = [vk::PushConstantRange {
        stage_flags: vk::ShaderStageFlags::ALL,
        offset: 0,
        size: push_size,
    }];
    let info = vk::PipelineLayoutCreateInfo::default()
        .set_layouts(&raw_sets)
        .push_constant_ranges(if push_size > 0 { &ranges[..] } else { &[] });
    Ok(unsafe { ctx.device.create_pipeline_layout(&info, None) }?)
}

/// The store's key for a pipeline of `stages` over `sets` (see
/// `pipeline_store`): the set layouts by description, not by handle.
pub(super) fn pipeline_key(
    stages: Stages,
    specialization: &Specialization,
    sets: &[&DescriptorSetLayout],
    push_size: u32,
) -> PipelineKey {
    PipelineKey {
        stages,
        specialization: specialization.clone(),
        sets: sets
            .iter()
            .map(|s| {
                s.bindings
                    .iter()
                    .map(|&(b, k)| (b, k.descriptor_type()))
                    .collect()
            })
            .collect(),
        push_size,
    }
}

/// Every shader's entry point.
const ENTRY_POINT: &CStr = c"main";

/// Makes the shader modules of `stages`, calls `create` with their stage
/// infos (specialised by `specialization`) and a new pipeline layout, and
/// destroys the modules; on failure the layout too.
pub(super) fn create_with_stages(
    ctx: &Context,
    stages: &[(vk::ShaderStageFlags, &str)],
    specialization: &Specialization,
    sets: &[&DescriptorSetLayout],
    push_size: u32,
    create: impl FnOnce(
        &[vk::PipelineShaderStageCreateInfo],
        vk::PipelineLayout,
    ) -> Result<Vec<vk::Pipeline>, (Vec<vk::Pipeline>, vk::Result)>,
) -> VkResult<(vk::Pipeline, vk::PipelineLayout)> {
    let mut modules = Vec::with_capacity(stages.len());
    for &(stage, name) in stages {
        match shader_module(ctx, name) {
            Ok(m) => modules.push((stage, m)),
            Err(e) => {
                for (_, m) in modules {
                    unsafe { ctx.device.destroy_shader_module(m, None) };
                }
                return Err(e);
            }
        }
    }
    let (map, data) = specialization.raw();
    let spec_info = vk::SpecializationInfo::default()
        .map_entries(&map)
        .data(&data);
    let infos: Vec<_> = modules
        .iter()
        .map(|&(stage, module)| {
            vk::PipelineShaderStageCreateInfo::default()
                .stage(stage)
                .module(module)
                .name(ENTRY_POINT)
                .specialization_info(&spec_info)
        })
        .collect();
    let result =
        pipeline_layout(ctx, sets, push_size).and_then(|layout| match create(&infos, layout) {
            Ok(p) => Ok((p[0], layout)),
            Err((_, e)) => {
                unsafe { ctx.device.destroy_pipeline_layout(layout, None) };
                Err(e.into())
            }
        });
    for (_, m) in modules {
        unsafe { ctx.device.destroy_shader_module(m, None) };
    }
    result
}

/// Creates a graphics pipeline of `stages` with `desc`'s fixed-function
/// state; dynamic rendering into `desc`'s formats, viewport and scissor
/// dynamic.
pub(super) fn create_graphics(
    ctx: &Context,
    desc: &GraphicsPipelineDesc,
    stages: &[vk::PipelineShaderStageCreateInfo],
    layout: vk::PipelineLayout,
    cache: vk::PipelineCache,
) -> Result<Vec<vk::Pipeline>, (Vec<vk::Pipeline>, vk::Result)> {
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(desc.cull)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let multisample = vk::PipelineMultisampleStateCreateInfo::default()
        .rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let depth = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(desc.depth_test)
        .depth_write_enable(desc.depth_write)
        .depth_compare_op(vk::CompareOp::LESS_OR_EQUAL);
    let attachment = if desc.additive {
        vk::PipelineColorBlendAttachmentState::default()
            .blend_enable(true)
            .src_color_blend_factor(vk::BlendFactor::ONE)
            .dst_color_blend_factor(vk::BlendFactor::ONE)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ONE)
            .dst_alpha_blend_factor(vk::BlendFactor::ONE)
            .alpha_blend_op(if desc.alpha_min {
                vk::BlendOp::MIN
            } else {
                vk::BlendOp::ADD
            })
            .color_write_mask(vk::ColorComponentFlags::RGBA)
    } else {
        vk::PipelineColorBlendAttachmentState::default()
            .color_write_mask(vk::ColorComponentFlags::RGBA)
    };
    let attachments = vec![attachment; desc.color_formats.len()];
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let mut rendering = vk::PipelineRenderingCreateInfo::default()
        .color_attachment_formats(&desc.color_formats)
        .depth_attachment_format(desc.depth_format.unwrap_or(vk::Format::UNDEFINED));
    let info = vk::GraphicsPipelineCreateInfo::default()
        .stages(stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .depth_stencil_state(&depth)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(layout)
        .push_next(&mut rendering);
    unsafe { ctx.device.create_graphics_pipelines(cache, &[info], None) }
}
