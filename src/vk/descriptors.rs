//! Descriptor set layouts and sets, and samplers. Bindings are declared by
//! number (constants shared with GLSL through `shader_bindings.rs` or a
//! technique's `bindings.rs`), never by call order; image bindings are
//! written by the passes' declarations (`pass.rs`). No caller lists a
//! layout's bindings: a layout is what its shaders use
//! (`DescriptorSetLayout::of_shaders`, reflected by `reflect.rs`) or what a
//! set made whole is given (`DescriptorSet::of_resources`).

use super::reflect::BindingKind;
use super::{Buffer, Context, Image, VkResult};
use ash::vk;
use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;
use std::sync::Arc;

pub struct DescriptorSetLayout {
    ctx: Arc<Context>,
    pub raw: vk::DescriptorSetLayout,
    pub(super) bindings: Vec<(u32, BindingKind)>,
}

impl DescriptorSetLayout {
    /// Every binding is visible to all stages: sets are shared between compute
    /// and graphics passes, and the cost of wide stage masks is nil.
    fn new(ctx: &Arc<Context>, bindings: &[(u32, BindingKind)]) -> VkResult<Self> {
        let raw_bindings: Vec<_> = bindings
            .iter()
            .map(|&(binding, kind)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(binding)
                    .descriptor_type(kind.descriptor_type())
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::ALL)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&raw_bindings);
        let raw = unsafe { ctx.device.create_descriptor_set_layout(&info, None) }?;
        Ok(Self {
            ctx: ctx.clone(),
            raw,
            bindings: bindings.to_vec(),
        })
    }
}

impl DescriptorSetLayout {
    /// The layout of descriptor set `set` as `shaders` (paths under
    /// `glsl/`) use it: the union of the bindings their SPIR-V uses
    /// (`reflect.rs`), so the shaders are the one list of a set's bindings.
    /// The shaders that share a set must agree on each binding's kind.
    pub fn of_shaders(ctx: &Arc<Context>, set: u32, shaders: &[&str]) -> VkResult<Self> {
        let mut union: BTreeMap<u32, (BindingKind, &str)> = BTreeMap::new();
        for &name in shaders {
            let used = super::reflect::bindings(&crate::shaders::spirv(name))
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            for b in used.into_iter().filter(|b| b.set == set) {
                let (kind, first) = *union.entry(b.binding).or_insert((b.kind, name));
                assert!(
                    kind == b.kind,
                    "set {set} binding {}: {kind:?} in {first} but {:?} in {name}",
                    b.binding,
                    b.kind
                );
            }
        }
        let bindings: Vec<_> = union.into_iter().map(|(b, (k, _))| (b, k)).collect();
        Self::new(ctx, &bindings)
    }
}

impl Drop for DescriptorSetLayout {
    fn drop(&mut self) {
        unsafe {
            self.ctx
                .device
                .destroy_descriptor_set_layout(self.raw, None)
        };
    }
}

/// What one binding of a set points at: the resource's unique id, the view
/// (an image's whole view or one of its level views), the layout and the
/// sampler. A pass's declaration writes a binding only when this changes.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Bound {
    pub id: u64,
    pub view: vk::ImageView,
    pub layout: vk::ImageLayout,
    pub sampler: vk::Sampler,
}

impl Bound {
    /// `image` through `view` in `layout`, with `sampler` (null for a
    /// storage image).
    pub(super) fn image(
        image: &Image,
        view: vk::ImageView,
        layout: vk::ImageLayout,
        sampler: vk::Sampler,
    ) -> Bound {
        Bound {
            id: image.id,
            view,
            layout,
            sampler,
        }
    }

    pub(super) fn buffer(buffer: &Buffer) -> Bound {
        Bound {
            id: buffer.id,
            view: vk::ImageView::null(),
            layout: vk::ImageLayout::UNDEFINED,
            sampler: vk::Sampler::null(),
        }
    }
}

/// One descriptor set with its own small pool (sets are few and long-lived here).
pub struct DescriptorSet {
    ctx: Arc<Context>,
    pool: vk::DescriptorPool,
    pub raw: vk::DescriptorSet,
    bindings: Vec<(u32, BindingKind)>,
    /// What each written binding points at.
    contents: RefCell<Vec<(u32, Bound)>>,
    /// The serial of the last frame whose command buffer bound this set
    /// (0: none): a binding may not change after the set was bound in the
    /// frame being recorded (that would invalidate the command buffer).
    pub(super) bound_in: Cell<u64>,
}

/// What a binding of a set made whole by `DescriptorSet::of_resources`
/// points at.
pub enum SetResource<'a> {
    /// A uniform or storage buffer: its kind is its usage's.
    Buffer(&'a Buffer),
    /// An uploaded texture and its sampler (`write_static_texture`).
    Texture(&'a Image, &'a Sampler),
}

impl DescriptorSet {
    /// A set whose every binding is fixed when it is made (the scene's),
    /// with its layout: the bindings are `resources`, each named once, on
    /// the line that gives its resource.
    pub fn of_resources(
        ctx: &Arc<Context>,
        resources: &[(u32, SetResource)],
    ) -> VkResult<(DescriptorSetLayout, DescriptorSet)> {
        let bindings: Vec<_> = resources
            .iter()
            .map(|(binding, resource)| {
                let kind = match resource {
                    SetResource::Buffer(buffer) => match buffer.usage {
                        super::BufferUsage::Uniform => BindingKind::Uniform,
                        super::BufferUsage::Storage | super::BufferUsage::StorageIndirect => {
                            BindingKind::Storage
                        }
                        other => panic!("binding {binding}: a {other:?} buffer cannot be bound"),
                    },
                    SetResource::Texture(..) => BindingKind::Sampled,
                };
                (*binding, kind)
            })
            .collect();
        let layout = DescriptorSetLayout::new(ctx, &bindings)?;
        let set = DescriptorSet::new(ctx, &layout)?;
        for (binding, resource) in resources {
            match resource {
                SetResource::Buffer(buffer) => set.write_buffer(*binding, buffer),
                SetResource::Texture(image, sampler) => {
                    set.write_static_texture(*binding, image, sampler)
                }
            };
        }
        Ok((layout, set))
    }

    pub fn new(ctx: &Arc<Context>, layout: &DescriptorSetLayout) -> VkResult<Self> {
        let sizes: Vec<_> = layout
            .bindings
            .iter()
            .map(|(_, k)| vk::DescriptorPoolSize {
                ty: k.descriptor_type(),
                descriptor_count: 1,
            })
            .collect();
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(1)
            .pool_sizes(&sizes);
        let pool = unsafe { ctx.device.create_descriptor_pool(&info, None) }?;
        let layouts = [layout.raw];
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(pool)
            .set_layouts(&layouts);
        let raw = match unsafe { ctx.device.allocate_descriptor_sets(&alloc) } {
            Ok(s) => s[0],
            Err(e) => {
                unsafe { ctx.device.destroy_descriptor_pool(pool, None) };
                return Err(e.into());
            }
        };
        Ok(Self {
            ctx: ctx.clone(),
            pool,
            raw,
            bindings: layout.bindings.clone(),
            contents: RefCell::new(Vec::new()),
            bound_in: Cell::new(0),
        })
    }

    fn kind_of(&self, binding: u32) -> BindingKind {
        self.bindings
            .iter()
            .find(|(b, _)| *b == binding)
            .map(|(_, k)| *k)
            .unwrap_or_else(|| panic!("binding {binding} is not in this set's layout"))
    }

    /// Points a uniform or storage buffer binding at `buffer`. For buffers
    /// bound once at construction (no layout to keep in step); a pass that
    /// must also order its accesses declares the binding instead (`Pass::buffer`).
    pub fn write_buffer(&self, binding: u32, buffer: &Buffer) -> &Self {
        buffer.bound.set(true);
        let info = [buffer.descriptor_info()];
        let write = vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(self.kind_of(binding).descriptor_type())
            .buffer_info(&info);
        unsafe { self.ctx.device.update_descriptor_sets(&[write], &[]) };
        self.remember(binding, Bound::buffer(buffer));
        self
    }

    /// Points each binding of `buffers` that this set's layout has at its
    /// buffer (sets of one technique's passes share the buffers).
    pub fn write_buffers(&self, buffers: &[(u32, &Buffer)]) -> &Self {
        for &(binding, buffer) in buffers {
            if self.bindings.iter().any(|(b, _)| *b == binding) {
                self.write_buffer(binding, buffer);
            }
        }
        self
    }

    /// Points a texture binding at an image that is never written again
    /// after its upload (a scene's textures), in the layout the upload left
    /// it in: read from the image's tracked state, so it cannot disagree.
    pub fn write_static_texture(&self, binding: u32, image: &Image, sampler: &Sampler) -> &Self {
        let layout = image.layout();
        assert!(
            layout == vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            "a static texture must be uploaded (and in SHADER_READ_ONLY_OPTIMAL) before it is bound"
        );
        self.write_image(
            binding,
            Bound::image(image, image.view, layout, sampler.raw),
        );
        self
    }

    /// What `binding` points at now, if it was written.
    pub(super) fn bound(&self, binding: u32) -> Option<Bound> {
        self.contents
            .borrow()
            .iter()
            .find(|(b, _)| *b == binding)
            .map(|&(_, bound)| bound)
    }

    fn remember(&self, binding: u32, bound: Bound) {
        let mut contents = self.contents.borrow_mut();
        match contents.iter_mut().find(|(b, _)| *b == binding) {
            Some(entry) => entry.1 = bound,
            None => contents.push((binding, bound)),
        }
    }

    /// Writes an image binding (storage image or combined image sampler, as
    /// the layout says) and remembers it.
    pub(super) fn write_image(&self, binding: u32, bound: Bound) {
        let kind = self.kind_of(binding);
        let info = [vk::DescriptorImageInfo::default()
            .image_view(bound.view)
            .sampler(bound.sampler)
            .image_layout(bound.layout)];
        let write = vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(kind.descriptor_type())
            .image_info(&info);
        unsafe { self.ctx.device.update_descriptor_sets(&[write], &[]) };
        self.remember(binding, bound);
    }
}

impl Drop for DescriptorSet {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_descriptor_pool(self.pool, None) };
    }
}

pub struct Sampler {
    ctx: Arc<Context>,
    pub raw: vk::Sampler,
}

impl Sampler {
    pub fn new(ctx: &Arc<Context>, filter: vk::Filter) -> VkResult<Self> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0);
        Ok(Self {
            ctx: ctx.clone(),
            raw: unsafe { ctx.device.create_sampler(&info, None) }?,
        })
    }
}

impl Sampler {
    /// Trilinear filtering over every mip level with `address` in u and v
    /// (clamped in w).
    fn trilinear(ctx: &Arc<Context>, address: vk::SamplerAddressMode) -> VkResult<Self> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
            .address_mode_u(address)
            .address_mode_v(address)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(vk::LOD_CLAMP_NONE);
        Ok(Self {
            ctx: ctx.clone(),
            raw: unsafe { ctx.device.create_sampler(&info, None) }?,
        })
    }

    /// Trilinear filtering with repeat wrap over every mip level (tiling
    /// textures).
    pub fn repeat_mipmapped(ctx: &Arc<Context>) -> VkResult<Self> {
        Self::trilinear(ctx, vk::SamplerAddressMode::REPEAT)
    }

    /// Trilinear filtering, clamped to the edge, over every mip level: for
    /// `textureGrad` lookups with explicit footprints.
    pub fn trilinear_clamp(ctx: &Arc<Context>) -> VkResult<Self> {
        Self::trilinear(ctx, vk::SamplerAddressMode::CLAMP_TO_EDGE)
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_sampler(self.raw, None) };
    }
}
