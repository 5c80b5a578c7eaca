//! The scene on the GPU: geometry, materials, textures with mip chains, lights and their
//! shadow views. Uploaded once through a staging buffer.

use super::area_lights::{AreaLight, MAX_AREA_CORNERS};
use super::gpu::{
    area_tables, as_bytes, AreaTables, GpuLight, GpuMaterial, ShadowView, MAX_LIGHTS,
    MAX_SHADOW_VIEWS,
};
use super::shadows::{light_views, soft_shadow_texels, LightViews};
use crate::scene::{Aabb, Light, Scene, Texture, Wrap};
use crate::vk::{
    vk, Access, Buffer, Context, Graph, Image, ImageDesc, ResourceStates, Sampler, VkError,
    VkResult,
};
use gpu_allocator::MemoryLocation;
use std::collections::HashMap;
use std::sync::Arc;

pub struct GpuScene {
    pub vertices: Buffer,
    pub indices: Buffer,
    /// Each material's factors (glsl/material.glsl: MaterialFactors), `material_stride` bytes
    /// apart.
    pub materials: Buffer,
    pub material_stride: u64,
    pub lights: LightBuffers,
    pub textures: Vec<Image>,
    /// Which sampler each texture uses.
    pub texture_samplers: Vec<usize>,
    pub samplers: Vec<Sampler>,
    pub light_views: Vec<LightViews>,
    /// The environment's image (black, 1x1, without one) and its sampler.
    pub environment: Image,
    pub environment_sampler: Sampler,
    pub shadow_view_count: u32,
    /// The scene's punctual lights' views (the area lights' follow them).
    pub punctual_view_count: u32,
}

/// The lights, their shadow views and the area lights' shapes (host-visible: rewritten when an
/// area light moves), and the LTC table.
pub struct LightBuffers {
    pub lights: Buffer,
    pub shadow_views: Buffer,
    pub area_polygons: Buffer,
    pub area_vertices: Buffer,
    pub area_edges: Buffer,
    pub ltc: Buffer,
}

impl LightBuffers {
    fn new(ctx: &Arc<Context>, table: &LightTable) -> VkResult<LightBuffers> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let uniform = vk::BufferUsageFlags::UNIFORM_BUFFER;
        // Uniform blocks at their declared size (glsl/common.glsl, glsl/area_lights.glsl).
        fn full<T: Copy + Default>(v: &[T], size: usize) -> Vec<T> {
            // Counts are checked below, or bounded by MAX_AREA_LIGHTS x MAX_EDGES.
            assert!(v.len() <= size, "{} entries for a block of {size}", v.len());
            let mut v = v.to_vec();
            v.resize(size, T::default());
            v
        }
        let views = table.shadow_views();
        if table.lights.len() > MAX_LIGHTS {
            return Err(VkError::Request(format!(
                "the scene has {} lights (its punctual lights and emissive surfaces as area \
                 lights); voxgi renders at most {MAX_LIGHTS}",
                table.lights.len()
            )));
        }
        if views.len() > MAX_SHADOW_VIEWS {
            return Err(VkError::Request(format!(
                "the scene's lights need {} shadow views (six per point light or emissive \
                 surface); voxgi renders at most {MAX_SHADOW_VIEWS}",
                views.len()
            )));
        }
        Ok(LightBuffers {
            lights: Buffer::with_data(
                ctx,
                "lights",
                as_bytes(&full(&table.lights, MAX_LIGHTS)),
                uniform,
            )?,
            shadow_views: Buffer::with_data(
                ctx,
                "shadow views",
                as_bytes(&full(&views, MAX_SHADOW_VIEWS)),
                uniform,
            )?,
            area_polygons: Buffer::with_data(
                ctx,
                "area polygons",
                as_bytes(&full(&table.area.polygons, MAX_AREA_CORNERS)),
                uniform,
            )?,
            area_vertices: Buffer::with_data(
                ctx,
                "area vertices",
                as_bytes(&full(&table.area.vertices, MAX_AREA_CORNERS)),
                uniform,
            )?,
            area_edges: Buffer::with_data(
                ctx,
                "area edges",
                as_bytes(&full(&table.area.edges, MAX_AREA_CORNERS)),
                uniform,
            )?,
            ltc: Buffer::with_data(ctx, "LTC table", as_bytes(super::ltc::gpu_table()), storage)?,
        })
    }

    /// Writes a table of the same lights and shapes (moved); the frame before was waited for.
    pub fn write(&mut self, table: &LightTable) {
        let views = table.shadow_views();
        if !table.lights.is_empty() {
            self.lights.write(0, as_bytes(&table.lights));
        }
        if !views.is_empty() {
            self.shadow_views.write(0, as_bytes(&views));
        }
        if !table.area.polygons.is_empty() {
            self.area_polygons.write(0, as_bytes(&table.area.polygons));
            self.area_vertices.write(0, as_bytes(&table.area.vertices));
        }
        if !table.area.edges.is_empty() {
            self.area_edges.write(0, as_bytes(&table.area.edges));
        }
    }
}

/// The lights as the shaders read them, their shadow views and the area lights' shapes.
pub struct LightTable {
    pub views: Vec<LightViews>,
    pub lights: Vec<GpuLight>,
    pub area: AreaTables,
}

impl LightTable {
    /// Every light's shadow views in order.
    fn shadow_views(&self) -> Vec<ShadowView> {
        self.views
            .iter()
            .flat_map(|v| v.views.iter().copied())
            .collect()
    }
}

/// Texels per side of the punctual lights' shadow views and of the area lights'.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowResolution {
    pub punctual: u32,
    pub area: u32,
}

/// The scene's lights in order, then the area lights (each seen from its centre through six
/// views of `resolution.area` texels, widened for the softest shadow's filter:
/// shadows::SOFT_SHADOW_SHARE).
pub fn light_table(
    lights: &[Light],
    area: &[AreaLight],
    bounds: &Aabb,
    resolution: ShadowResolution,
    pcf_radius: u32,
) -> LightTable {
    let mut views = light_views(lights, bounds, resolution.punctual, pcf_radius);
    let points: Vec<Light> = area.iter().map(AreaLight::as_point_light).collect();
    let first = views.iter().map(|v| v.views.len() as u32).sum::<u32>();
    let soft = soft_shadow_texels(resolution.area).max(pcf_radius);
    let mut area_views = light_views(&points, bounds, resolution.area, soft);
    for v in &mut area_views {
        v.first += first;
    }
    let tables = area_tables(area);
    let gpu = lights
        .iter()
        .zip(&views)
        .map(|(l, v)| GpuLight::from_light(l, v.first, v.views.len() as u32))
        .chain(
            area.iter()
                .zip(&area_views)
                .zip(&tables.ranges)
                .map(|((l, v), r)| GpuLight::from_area(l, r, v.first, v.views.len() as u32)),
        )
        .collect();
    views.extend(area_views);
    LightTable {
        views,
        lights: gpu,
        area: tables,
    }
}

/// The scene's textures (then a 1x1 white one, bound wherever a material has none): their
/// images, the copies of their mip levels from the staging data, and their samplers.
struct SceneTextures {
    textures: Vec<Image>,
    /// Per texture: one copy per mip level.
    regions: Vec<Vec<vk::BufferImageCopy>>,
    /// Per texture: its sampler's index in `samplers`.
    texture_samplers: Vec<usize>,
    samplers: Vec<Sampler>,
}

/// Makes the textures' images and stages their mip chains with `stage` (which returns each
/// chunk's offset in the staging data).
fn scene_textures(
    ctx: &Arc<Context>,
    scene: &Scene,
    stage: &mut impl FnMut(&[u8]) -> u64,
) -> VkResult<SceneTextures> {
    let white = white_texture();
    let tex_list: Vec<&Texture> = scene.textures.iter().chain([&white]).collect();
    let mut out = SceneTextures {
        textures: Vec::new(),
        regions: Vec::new(),
        texture_samplers: Vec::new(),
        samplers: Vec::new(),
    };
    let mut sampler_keys: HashMap<(i32, i32, bool, bool), usize> = HashMap::new();
    for (i, t) in tex_list.iter().enumerate() {
        let chain = mip_chain(t);
        let format = if t.srgb {
            vk::Format::R8G8B8A8_SRGB
        } else {
            vk::Format::R8G8B8A8_UNORM
        };
        let img = Image::new(
            ctx,
            &format!("texture {i} {}", t.name),
            ImageDesc::d2(
                format,
                t.width,
                t.height,
                vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            )
            .mips(chain.len() as u32),
        )?;
        let r = chain
            .iter()
            .enumerate()
            .map(|(level, (w, h, data))| mip_copy(stage(data), level as u32, *w, *h))
            .collect();
        out.regions.push(r);
        out.textures.push(img);
        let sampler = sampler_for(ctx, t, &mut sampler_keys, &mut out.samplers)?;
        out.texture_samplers.push(sampler);
    }
    Ok(out)
}

impl GpuScene {
    /// The 1x1 white texture (the last one).
    pub fn white(&self) -> usize {
        self.textures.len() - 1
    }
}

/// The mip chain of an RGBA8 image by 2x2 box filtering (in linear light for sRGB data).
pub fn mip_chain(tex: &Texture) -> Vec<(u32, u32, Vec<u8>)> {
    let to_linear = tex.linear_table();
    let encode = |v: f32| -> u8 {
        let v = v.clamp(0.0, 1.0);
        let e = if !tex.srgb {
            v
        } else if v <= 0.0031308 {
            v * 12.92
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (e * 255.0 + 0.5) as u8
    };
    let mut levels = vec![(tex.width, tex.height, tex.rgba8.clone())];
    loop {
        let (w, h, prev) = levels.last().unwrap();
        let (w, h) = (*w, *h);
        if w == 1 && h == 1 {
            break;
        }
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let mut next = vec![0u8; (nw * nh * 4) as usize];
        for y in 0..nh {
            for x in 0..nw {
                let xs = [(2 * x).min(w - 1), (2 * x + 1).min(w - 1)];
                let ys = [(2 * y).min(h - 1), (2 * y + 1).min(h - 1)];
                for c in 0..4 {
                    let mut sum = 0.0;
                    for &sy in &ys {
                        for &sx in &xs {
                            let v = prev[((sy * w + sx) * 4 + c) as usize];
                            // Alpha is always linear.
                            sum += if c == 3 {
                                v as f32 / 255.0
                            } else {
                                to_linear[v as usize]
                            };
                        }
                    }
                    let avg = sum * 0.25;
                    next[((y * nw + x) * 4 + c) as usize] = if c == 3 {
                        (avg.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
                    } else {
                        encode(avg)
                    };
                }
            }
        }
        levels.push((nw, nh, next));
    }
    levels
}

/// The materials as the shaders read them (a default one when the scene has none), each at an
/// offset a uniform buffer binding may start at, and their stride. Each material's set binds its
/// own: a draw reads its factors as uniforms, the same for every fragment.
fn material_buffer(ctx: &Arc<Context>, scene: &Scene) -> VkResult<(Buffer, u64)> {
    let mats: Vec<GpuMaterial> = scene
        .materials
        .iter()
        .map(GpuMaterial::from_material)
        .collect();
    let mats = if mats.is_empty() {
        vec![GpuMaterial::default()]
    } else {
        mats
    };
    let size = std::mem::size_of::<GpuMaterial>() as u64;
    let align = ctx
        .properties
        .limits
        .min_uniform_buffer_offset_alignment
        .max(1);
    let stride = size.div_ceil(align) * align;
    let mut bytes = vec![0u8; (stride * mats.len() as u64) as usize];
    for (i, m) in mats.iter().enumerate() {
        let at = i * stride as usize;
        bytes[at..at + size as usize].copy_from_slice(as_bytes(std::slice::from_ref(m)));
    }
    let buffer = Buffer::with_data(
        ctx,
        "materials",
        &bytes,
        vk::BufferUsageFlags::UNIFORM_BUFFER,
    )?;
    Ok((buffer, stride))
}

/// The 1x1 white texture bound wherever a material has none.
fn white_texture() -> Texture {
    Texture {
        name: "white".into(),
        width: 1,
        height: 1,
        rgba8: vec![255; 4],
        srgb: false,
        wrap_s: Wrap::Repeat,
        wrap_t: Wrap::Repeat,
        mag_nearest: false,
        min_nearest: false,
    }
}

/// The copy of one mip level from the staging buffer at `offset`.
fn mip_copy(offset: u64, level: u32, width: u32, height: u32) -> vk::BufferImageCopy {
    let extent = vk::Extent3D {
        width,
        height,
        depth: 1,
    };
    crate::vk::level_copy(offset, level, extent)
}

/// The sampler of a texture's wrap and filter modes: one per distinct set, made on first use.
fn sampler_for(
    ctx: &Arc<Context>,
    t: &Texture,
    keys: &mut HashMap<(i32, i32, bool, bool), usize>,
    samplers: &mut Vec<Sampler>,
) -> VkResult<usize> {
    let key = (
        address_mode(t.wrap_s).as_raw(),
        address_mode(t.wrap_t).as_raw(),
        t.mag_nearest,
        t.min_nearest,
    );
    if let Some(&i) = keys.get(&key) {
        return Ok(i);
    }
    let filter = |nearest: bool| {
        if nearest {
            vk::Filter::NEAREST
        } else {
            vk::Filter::LINEAR
        }
    };
    let info = vk::SamplerCreateInfo::default()
        .mag_filter(filter(t.mag_nearest))
        .min_filter(filter(t.min_nearest))
        .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
        .address_mode_u(address_mode(t.wrap_s))
        .address_mode_v(address_mode(t.wrap_t))
        .address_mode_w(vk::SamplerAddressMode::REPEAT)
        // Anisotropic filtering makes no sense with nearest filtering (and blends texels on
        // some drivers).
        .anisotropy_enable(!t.min_nearest)
        .max_anisotropy(ctx.properties.limits.max_sampler_anisotropy.min(8.0))
        .max_lod(vk::LOD_CLAMP_NONE);
    samplers.push(Sampler::new(ctx, &info)?);
    keys.insert(key, samplers.len() - 1);
    Ok(samplers.len() - 1)
}

fn address_mode(w: Wrap) -> vk::SamplerAddressMode {
    match w {
        Wrap::Repeat => vk::SamplerAddressMode::REPEAT,
        Wrap::MirroredRepeat => vk::SamplerAddressMode::MIRRORED_REPEAT,
        Wrap::ClampToEdge => vk::SamplerAddressMode::CLAMP_TO_EDGE,
    }
}

impl GpuScene {
    /// `lights`: the scene's and the environment's sun; `environment`: the one the cones see
    /// (without its sun).
    #[allow(clippy::too_many_arguments)]
    pub fn upload(
        ctx: &Arc<Context>,
        scene: &Scene,
        lights: &[Light],
        environment: Option<&crate::scene::Environment>,
        states: &mut ResourceStates,
        area_lights: &[AreaLight],
        shadow_resolution: ShadowResolution,
        pcf_radius: u32,
    ) -> VkResult<GpuScene> {
        let mut staging = Staging::default();
        let (vertices, vertex_off) = staged_buffer(
            ctx,
            "scene vertices",
            as_bytes(&scene.vertices),
            vk::BufferUsageFlags::VERTEX_BUFFER,
            &mut staging,
        )?;
        let (indices, index_off) = staged_buffer(
            ctx,
            "scene indices",
            as_bytes(&scene.indices),
            vk::BufferUsageFlags::INDEX_BUFFER,
            &mut staging,
        )?;

        // Materials, lights and shadow views are small: host-visible buffers, written once.
        let (materials, material_stride) = material_buffer(ctx, scene)?;

        let table = light_table(
            lights,
            area_lights,
            &scene.bounds,
            shadow_resolution,
            pcf_radius,
        );
        let light_buffers = LightBuffers::new(ctx, &table)?;

        let SceneTextures {
            mut textures,
            mut regions,
            texture_samplers,
            samplers,
        } = scene_textures(ctx, scene, &mut |bytes| staging.push(bytes))?;
        // The environment goes up with the textures.
        let env_levels = super::environment::levels(environment);
        textures.push(super::environment::image(ctx, &env_levels)?);
        regions.push(
            env_levels
                .iter()
                .enumerate()
                .map(|(level, (w, h, data))| mip_copy(staging.push(data), level as u32, *w, *h))
                .collect(),
        );

        let copies = [(&vertices, vertex_off), (&indices, index_off)];
        staging.upload(ctx, states, &copies, &textures, &regions)?;
        let environment = textures.pop().expect("the environment was pushed last");

        Ok(GpuScene {
            vertices,
            indices,
            materials,
            material_stride,
            lights: light_buffers,
            textures,
            texture_samplers,
            samplers,
            shadow_view_count: table.views.iter().map(|v| v.views.len() as u32).sum(),
            punctual_view_count: table.views[..lights.len()]
                .iter()
                .map(|v| v.views.len() as u32)
                .sum(),
            light_views: table.views,
            environment,
            environment_sampler: super::environment::sampler(ctx)?,
        })
    }
}

/// The bytes of everything uploaded at load, gathered into one staging buffer.
#[derive(Default)]
struct Staging {
    data: Vec<u8>,
}

impl Staging {
    /// Appends `bytes`; returns their offset.
    fn push(&mut self, bytes: &[u8]) -> u64 {
        // 16-byte alignment satisfies every copy's offset rules.
        while !self.data.len().is_multiple_of(16) {
            self.data.push(0);
        }
        let off = self.data.len() as u64;
        self.data.extend_from_slice(bytes);
        off
    }

    /// Copies the staged bytes into the buffers (from their offsets) and the textures (by
    /// their regions) in one command buffer, and waits for it.
    fn upload(
        self,
        ctx: &Arc<Context>,
        states: &mut ResourceStates,
        buffers: &[(&Buffer, Staged)],
        textures: &[Image],
        regions: &[Vec<vk::BufferImageCopy>],
    ) -> VkResult<()> {
        let mut staging = Buffer::new(
            ctx,
            "scene staging",
            self.data.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        staging.write(0, &self.data);
        ctx.one_shot(|cmd| {
            let mut g = Graph::new(ctx, cmd, states, None);
            let mut pass = g.pass("upload").buffer(&staging, Access::TransferRead);
            for (b, _) in buffers {
                pass = pass.buffer(b, Access::TransferWrite);
            }
            for t in textures {
                pass = pass.image(t, Access::TransferWrite);
            }
            pass.record(|cmd| unsafe {
                let d = &ctx.device;
                for (b, staged) in buffers {
                    // An empty scene's buffers are placeholders: nothing to copy.
                    if staged.len > 0 {
                        let region = vk::BufferCopy {
                            src_offset: staged.offset,
                            dst_offset: 0,
                            size: staged.len,
                        };
                        d.cmd_copy_buffer(cmd, staging.raw, b.raw, &[region]);
                    }
                }
                for (t, r) in textures.iter().zip(regions) {
                    d.cmd_copy_buffer_to_image(
                        cmd,
                        staging.raw,
                        t.raw,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        r,
                    );
                }
            });
        })?;
        states.forget(staging.raw);
        Ok(())
    }
}

/// Where a buffer's bytes lie in the staging buffer.
#[derive(Clone, Copy)]
struct Staged {
    offset: u64,
    len: u64,
}

/// A device-local buffer for `bytes` (with `usage`), its bytes staged.
fn staged_buffer(
    ctx: &Arc<Context>,
    name: &str,
    bytes: &[u8],
    usage: vk::BufferUsageFlags,
    staging: &mut Staging,
) -> VkResult<(Buffer, Staged)> {
    let buffer = Buffer::new(
        ctx,
        name,
        bytes.len() as u64,
        usage | vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuOnly,
    )?;
    let staged = Staged {
        offset: staging.push(bytes),
        len: bytes.len() as u64,
    };
    Ok((buffer, staged))
}
