//! The GPU memory of the voxel passes: only what the scene and the settings need.

use super::{GiSettings, VoxelGrid};
use crate::vk::{
    vk, AddressTable, Bindings, Buffer, Context, Image, ImageDesc, Sampler, Usage, VkError,
    VkResult,
};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// uints per voxel of the default accumulators (glsl/voxel_common.glsl), in three buffers so
/// that each stays within a 2 GiB allocation at 512^3: the count and albedo sums, the normal
/// sums and where the surfaces cross the voxel, and the squared normals (spread) with the
/// luminance of the albedo's glossy part.
pub const ALBEDO_STRIDE: u64 = 4;
pub const NORMAL_STRIDE: u64 = 4;
pub const SPREAD_STRIDE: u64 = 4;
/// Emission sums: RGB weighted by coverage, then the emitting surfaces' coverage (fixed point,
/// voxelize.frag).
pub const EMISSION_STRIDE: u64 = 4;

/// The default's fixed-point sums of one voxelization pass (static or dynamic).
pub struct Sums {
    /// Count, then albedo r g b (ALBEDO_STRIDE words a voxel).
    pub albedo: Buffer,
    /// Normal, then where the surfaces cross the voxel (NORMAL_STRIDE words a voxel).
    pub normal: Buffer,
    /// Squared normal, then the luminance of the albedo's glossy part (SPREAD_STRIDE words a
    /// voxel).
    pub spread: Buffer,
    /// When the scene emits (EMISSION_STRIDE words a voxel).
    pub emission: Option<Buffer>,
}

impl Sums {
    fn buffers(&self) -> impl Iterator<Item = &Buffer> {
        [&self.albedo, &self.normal, &self.spread]
            .into_iter()
            .chain(&self.emission)
    }

    /// In the order of a pass's address table (glsl/voxel_common.glsl: WORDS_*).
    fn table(&self) -> [Option<&Buffer>; 4] {
        [
            Some(&self.albedo),
            Some(&self.normal),
            Some(&self.spread),
            self.emission.as_ref(),
        ]
    }
}

/// What voxelization writes, per mode (one per renderer: the variants' sizes do not matter).
#[allow(clippy::large_enum_variant)]
pub enum VoxelData {
    /// Fixed-point sums and counts: static pass, and dynamic pass when there is dynamic geometry.
    Sums {
        static_sums: Sums,
        dynamic_sums: Option<Box<Sums>>,
    },
    /// The paper's RGBA8 moving averages in r32ui 3D images, and its static flags.
    Paper(PaperVolumes),
}

/// The original's voxel volumes: RGBA8 moving averages in 3D storage images, written through
/// r32ui views (the bits of an RGBA8 texel, averaged by imageAtomicCompSwap) and read through
/// RGBA8 views, and its R8 static flags. Emission and flags are one texel, never read, where
/// the scene emits nothing or nothing moves: the shaders' bindings stay.
pub struct PaperVolumes {
    pub albedo: Image,
    pub normal: Image,
    pub emission: Image,
    pub flag: Image,
    pub emissive: bool,
    pub dynamic: bool,
}

impl PaperVolumes {
    /// The volumes voxelization writes and the static pass clears (the flags where nodes move).
    pub fn images(&self) -> Vec<&Image> {
        let mut v = vec![&self.albedo, &self.normal];
        if self.emissive {
            v.push(&self.emission);
        }
        if self.dynamic {
            v.push(&self.flag);
        }
        v
    }

    /// Binds the averages' r32ui views as voxelize.frag names them (its atomics).
    pub fn bind_words(&self, table: Bindings, usage: Usage) -> Bindings {
        table
            .image("paper_albedo", &self.albedo, usage)
            .image("paper_normal", &self.normal, usage)
            .image("paper_emission", &self.emission, usage)
    }

    /// Binds the averages' RGBA8 views as glsl/voxel_data.glsl and clear_dynamic.comp name
    /// them (the original's later passes read them as RGBA8).
    pub fn bind_texels(&self, table: Bindings, usage: [Usage; 3]) -> Bindings {
        let rgba8 = |i: &Image| {
            i.format_view(PAPER_TEXELS)
                .expect("made with an RGBA8 view")
        };
        let [a, n, e] = usage;
        table
            .image_view("paper_albedo", &self.albedo, rgba8(&self.albedo), a)
            .image_view("paper_normal", &self.normal, rgba8(&self.normal), n)
            .image_view("paper_emission", &self.emission, rgba8(&self.emission), e)
    }
}

impl VoxelData {
    /// The buffers the static (or the dynamic) voxelization pass writes.
    pub fn written_by(&self, dynamic: bool) -> Vec<&Buffer> {
        match self {
            VoxelData::Sums {
                static_sums,
                dynamic_sums,
            } => match dynamic {
                true => dynamic_sums.iter().flat_map(|s| s.buffers()).collect(),
                false => static_sums.buffers().collect(),
            },
            // Images, not buffers (PaperVolumes::images).
            VoxelData::Paper(_) => Vec::new(),
        }
    }

    /// Every buffer of voxel words (what the lighting passes and views may read).
    pub fn buffers(&self) -> Vec<&Buffer> {
        let mut v = self.written_by(false);
        if let VoxelData::Sums { .. } = self {
            v.extend(self.written_by(true));
        }
        v
    }

    /// The buffers in the address tables of the static and the dynamic pass (none where
    /// absent; none for --paper, whose volumes are images).
    fn tables(&self) -> [[Option<&Buffer>; 4]; 2] {
        match self {
            VoxelData::Sums {
                static_sums,
                dynamic_sums,
            } => [
                static_sums.table(),
                dynamic_sums.as_ref().map_or([None; 4], |d| d.table()),
            ],
            VoxelData::Paper(_) => [[None; 4], [None; 4]],
        }
    }
}

/// Name and bytes of one volume, for `voxgi info`.
#[derive(Clone, Debug)]
pub struct VolumeInfo {
    pub name: String,
    pub bytes: u64,
}

pub struct Volumes {
    pub grid: VoxelGrid,
    pub data: VoxelData,
    /// Where the voxel words lie, per voxelization pass (static, dynamic): four device
    /// addresses each (VoxelData::addresses), which the shaders read from these small buffers
    /// and reach the words through (GL_EXT_buffer_reference): a 512^3 grid's sums are larger
    /// than a storage buffer's descriptor may span (maxStorageBufferRange: 128 MiB on
    /// lavapipe).
    pub words: [AddressTable; 2],
    /// Outgoing radiance per voxel, premultiplied by opacity (RGBA16F; RGBA8 for --paper).
    pub radiance: Image,
    /// The direction each voxel sends its light (RGBA8 signed, xyz; length 1: one side only,
    /// 0: every way), and in w where along it the voxel's surfaces lie from its centre (in
    /// voxels); the base mip level shows a voxel's light only in the directional volumes of
    /// cones it reaches, so that a wall's lit side does not show through its back, and cones
    /// see it only from in front of its surface. None for --paper, whose voxels shine every
    /// way.
    pub emit_dir: Option<Image>,
    /// Of each voxel's emission, the luminance (times the radiance scale) that comes from
    /// emitters covering less than the voxel (R32F). Such an emitter sends its light mostly
    /// along its normal, by the cosine, where a voxel shows one radiance to every side: from the
    /// side, cones see only part of it (aniso_mip_base.comp). One texel, never read, when the
    /// scene emits nothing; None for --paper.
    pub small_emission: Option<Image>,
    /// The light the backs of open-backed voxels reflect (RGBA16F, as the radiance volume's;
    /// `GiSettings::backs`, glsl/voxel_data.glsl's `open_back`). One texel, never read,
    /// without it; None for --paper.
    pub back_radiance: Option<Image>,
    /// The light of mirror-like specular lobes (RGBA16F, as the radiance volume's, without
    /// opacity): a voxel's glossy share of its light (glsl/voxel_data.glsl's `Voxel::glossy`),
    /// which goes one way and so is left out of the full-resolution volume that narrow cones
    /// read; the directional volumes hold it (glsl/aniso_mip_base.comp). None for --paper.
    pub glossy_radiance: Option<Image>,
    /// The six directional volumes (-X, +X, -Y, +Y, -Z, +Z) with full mip chains.
    pub faces: Vec<Image>,
    /// Beside the directional volumes, texel for texel: where their light goes (xyz, the
    /// voxels' light directions weighted by their luminance) and that weight (w), both divided
    /// by the voxels averaged. Cones see a texel's light only from the side it goes to. None
    /// for --paper.
    pub light_dir: Option<Image>,
    /// Beside it: where the texel's light lies (xyz: the voxels' surfaces, in grid units 0 to
    /// 1, weighted by luminance like the directions). Cones see a texel's light only from in
    /// front of the plane it leaves (a thin wall's lit face, which shares texels with the dark
    /// room beside it). None for --paper.
    pub light_pos: Option<Image>,
    /// Beside them, the thin walls (surfaces one voxel thick with empty voxels on both sides):
    /// per axis, how much of a texel's cross-section along it they cover (up to 1) and where
    /// along it they lie (grid units 0 to 1, times the cover); x and y in the first volume
    /// (x position, x cover, y position, y cover), z in the second. The bounce's cones do not
    /// see light behind a thin wall from their origin (glsl/cone_tracing.glsl's
    /// thin_wall_between). One-texel stand-ins, never read, without a bounce; None for --paper.
    pub thin_walls: Option<[Image; 2]>,
    /// Per cell of `grid.empty_space_cell()` voxels a side, the distance in cells to the
    /// nearest cell that holds a filled voxel (R32UI; src/gi/empty_space.rs). None for --paper;
    /// a one-texel stand-in, never read, without `GiSettings::empty_space`.
    pub empty_space: Option<Image>,
    /// Per block of [`BOUNCE_BLOCK`]^3 voxels, the bounce gather its one-sided voxels share
    /// (RGBA32F: light and closed share), and which voxel's plane it was made in (R32UI: its
    /// index + 1, 0 for none); glsl/inject_bounce.comp. None for --paper; one-texel stand-ins,
    /// never read, without a bounce or without `GiSettings::bounce_share`.
    pub bounce_blocks: Option<[Image; 2]>,
    /// Trilinear, transparent black outside the grid.
    pub sampler: Sampler,
    /// The same but from the nearest mip level only: the thin walls, which the bounce's cones
    /// read twice a sample (blending two levels cost the frame after a light moved a tenth
    /// more on lavapipe, for the same leaks).
    pub level_sampler: Sampler,
    pub info: Vec<VolumeInfo>,
}

impl Volumes {
    /// Whether the back radiance volume covers the grid (`GiSettings::backs`).
    pub fn holds_backs(&self) -> bool {
        self.back_radiance
            .as_ref()
            .is_some_and(|b| b.desc.extent.width == self.grid.resolution)
    }

    /// Whether the thin walls' volumes are as large as the directional volumes (a bounce reads
    /// them; else they are one-texel stand-ins, as are the directional volumes of a grid of 2).
    pub fn holds_thin_walls(&self) -> bool {
        self.thin_walls.as_ref().is_some_and(|[w, _]| {
            self.faces.first().is_some_and(|f| {
                (f.desc.extent.width, f.desc.mip_levels) == (w.desc.extent.width, w.desc.mip_levels)
            })
        })
    }

    /// The directional volumes and the volumes beside them (light direction and position, and
    /// the thin walls where a bounce reads them), which the mip passes write and the cones
    /// sample together.
    pub fn directional(&self) -> impl Iterator<Item = &Image> {
        let walls = self.thin_walls.iter().filter(|_| self.holds_thin_walls());
        self.faces
            .iter()
            .chain(&self.light_dir)
            .chain(&self.light_pos)
            .chain(walls.flatten())
    }

    pub fn new(
        ctx: &Arc<Context>,
        grid: VoxelGrid,
        settings: &GiSettings,
        emissive: bool,
        dynamic: bool,
    ) -> VkResult<Volumes> {
        let n = grid.resolution;
        let mut info = Vec::new();
        check_grid_fits(ctx, grid, settings)?;
        let data = voxel_data(ctx, grid, settings, emissive, dynamic, &mut info)?;

        let texels = Texels::of(settings);
        let radiance = radiance_volume(ctx, n, texels, &mut info)?;
        let emit_dir = light_direction_volume(ctx, n, settings, &mut info)?;
        let small_emission =
            Optional::small_emission().make(ctx, n, settings, emissive, &mut info)?;
        let back_radiance =
            Optional::back_radiance().make(ctx, n, settings, settings.backs, &mut info)?;
        let glossy_radiance =
            Optional::glossy_radiance().make(ctx, n, settings, true, &mut info)?;
        let (faces, face_bytes) = directional_volumes(ctx, grid, texels, &mut info)?;
        let light_dir = beside_directional(
            ctx,
            grid,
            settings,
            face_bytes,
            "light direction",
            &mut info,
        )?;
        let light_pos =
            beside_directional(ctx, grid, settings, face_bytes, "light position", &mut info)?;
        let thin_walls = thin_wall_volumes(ctx, grid, settings, face_bytes, &mut info)?;
        let empty_space = empty_space_volume(ctx, grid, settings, &mut info)?;
        let shared = settings.bounces >= 2 && settings.bounce_share;
        let blocks = n.div_ceil(BOUNCE_BLOCK);
        let gathers = Optional::bounce_blocks().make(ctx, blocks, settings, shared, &mut info)?;
        let firsts = Optional::bounce_firsts().make(ctx, blocks, settings, shared, &mut info)?;
        let bounce_blocks = gathers.zip(firsts).map(|(g, f)| [g, f]);
        let sampler = volume_sampler(ctx, settings.paper, vk::SamplerMipmapMode::LINEAR)?;
        let level_sampler = volume_sampler(ctx, settings.paper, vk::SamplerMipmapMode::NEAREST)?;
        let [s, d] = data.tables();
        let words = [
            AddressTable::new(ctx, "static voxel word addresses", &s)?,
            AddressTable::new(ctx, "dynamic voxel word addresses", &d)?,
        ];
        Ok(Volumes {
            grid,
            data,
            words,
            radiance,
            emit_dir,
            small_emission,
            back_radiance,
            glossy_radiance,
            faces,
            light_dir,
            light_pos,
            thin_walls,
            empty_space,
            bounce_blocks,
            sampler,
            level_sampler,
            info,
        })
    }
}

/// Voxels a side of the blocks whose one-sided voxels share a bounce gather
/// (glsl/inject_bounce.comp's BLOCK).
pub const BOUNCE_BLOCK: u32 = 4;

/// The radiance and directional volumes' texels: RGBA16F, or the paper's RGBA8.
#[derive(Clone, Copy)]
struct Texels {
    format: vk::Format,
    bytes: u64,
}

impl Texels {
    fn of(settings: &GiSettings) -> Texels {
        if settings.paper {
            Texels {
                format: vk::Format::R8G8B8A8_UNORM,
                bytes: 4,
            }
        } else {
            Texels {
                format: vk::Format::R16G16B16A16_SFLOAT,
                bytes: 8,
            }
        }
    }
}

fn volume_usage() -> vk::ImageUsageFlags {
    vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC
}

/// Each voxel's light (step 2's output), full resolution.
fn radiance_volume(
    ctx: &Arc<Context>,
    n: u32,
    texels: Texels,
    info: &mut Vec<VolumeInfo>,
) -> VkResult<Image> {
    let format = texels.format;
    let radiance = Image::new(
        ctx,
        "voxel radiance",
        ImageDesc::d3(format, n, volume_usage()),
    )?;
    info.push(VolumeInfo {
        name: format!("voxel radiance ({format:?})"),
        bytes: (n as u64).pow(3) * texels.bytes,
    });
    Ok(radiance)
}

/// The way each voxel's light goes (not for --paper).
fn light_direction_volume(
    ctx: &Arc<Context>,
    n: u32,
    settings: &GiSettings,
    info: &mut Vec<VolumeInfo>,
) -> VkResult<Option<Image>> {
    if settings.paper {
        return Ok(None);
    }
    let desc = ImageDesc::d3(vk::Format::R8G8B8A8_SNORM, n, volume_usage());
    info.push(VolumeInfo {
        name: "voxel light direction (RGBA8 signed)".into(),
        bytes: (n as u64).pow(3) * 4,
    });
    Some(Image::new(ctx, "voxel light direction", desc)).transpose()
}

/// A full-resolution volume that only some scenes or settings use (none for --paper): the
/// grid's size when `used`, else a one-texel stand-in (never read) that keeps the passes'
/// bindings; listed in `info` (as `label`) only when used.
struct Optional {
    name: &'static str,
    label: &'static str,
    format: vk::Format,
    texel_bytes: u64,
    usage: vk::ImageUsageFlags,
}

impl Optional {
    /// Emission of emitters too small to be area lights (used when the voxels emit).
    fn small_emission() -> Optional {
        Optional {
            name: "voxel emission of small emitters",
            label: "voxel emission of small emitters (R32F)",
            format: vk::Format::R32_SFLOAT,
            texel_bytes: 4,
            // Storage only: the inject pass writes it, the mip pass reads it, the readback
            // copies it.
            usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
        }
    }

    /// The backs' light (used with `GiSettings::backs`).
    fn back_radiance() -> Optional {
        Optional {
            name: "voxel radiance of open backs",
            label: "voxel radiance of open backs (RGBA16F)",
            format: vk::Format::R16G16B16A16_SFLOAT,
            texel_bytes: 8,
            usage: volume_usage(),
        }
    }

    /// The mirror-like lobes' light (always, but for --paper).
    fn glossy_radiance() -> Optional {
        Optional {
            name: "voxel radiance of glossy lobes",
            label: "voxel radiance of glossy lobes (RGBA16F)",
            format: vk::Format::R16G16B16A16_SFLOAT,
            texel_bytes: 8,
            usage: volume_usage(),
        }
    }

    /// The bounce's gathers shared per block (`GiSettings::bounce_share`).
    fn bounce_blocks() -> Optional {
        Optional {
            name: "bounce gathers of voxel blocks",
            label: "bounce gathers of 4x4x4 voxel blocks (RGBA32F)",
            format: vk::Format::R32G32B32A32_SFLOAT,
            texel_bytes: 16,
            usage: vk::ImageUsageFlags::STORAGE,
        }
    }

    /// Beside them, the voxel in whose plane each was made.
    fn bounce_firsts() -> Optional {
        Optional {
            name: "bounce gather planes of voxel blocks",
            label: "bounce gather planes of 4x4x4 voxel blocks (R32UI)",
            format: vk::Format::R32_UINT,
            texel_bytes: 4,
            usage: vk::ImageUsageFlags::STORAGE,
        }
    }

    /// An image `n` texels a side when used.
    fn make(
        &self,
        ctx: &Arc<Context>,
        n: u32,
        settings: &GiSettings,
        used: bool,
        info: &mut Vec<VolumeInfo>,
    ) -> VkResult<Option<Image>> {
        if settings.paper {
            return Ok(None);
        }
        if used {
            info.push(VolumeInfo {
                name: self.label.into(),
                bytes: (n as u64).pow(3) * self.texel_bytes,
            });
        }
        let side = if used { n } else { 1 };
        Image::new(ctx, self.name, ImageDesc::d3(self.format, side, self.usage)).map(Some)
    }
}

/// Step 3's six directional volumes with their mips; also the bytes of one of them.
fn directional_volumes(
    ctx: &Arc<Context>,
    grid: VoxelGrid,
    texels: Texels,
    info: &mut Vec<VolumeInfo>,
) -> VkResult<(Vec<Image>, u64)> {
    let m = grid.aniso_resolution();
    let levels = grid.mip_levels();
    let faces = ["-X", "+X", "-Y", "+Y", "-Z", "+Z"]
        .iter()
        .map(|f| {
            Image::new(
                ctx,
                &format!("directional volume {f}"),
                ImageDesc::d3(texels.format, m, volume_usage()).mips(levels),
            )
        })
        .collect::<VkResult<Vec<_>>>()?;
    let face_bytes: u64 = (0..levels)
        .map(|l| ((m >> l).max(1) as u64).pow(3) * texels.bytes)
        .sum();
    info.push(VolumeInfo {
        name: format!("6 directional volumes, {m}^3 with {levels} mips"),
        bytes: 6 * face_bytes,
    });
    Ok((faces, face_bytes))
}

/// A volume beside the directional ones, texel for texel (not for --paper).
fn beside_directional(
    ctx: &Arc<Context>,
    grid: VoxelGrid,
    settings: &GiSettings,
    face_bytes: u64,
    what: &str,
    info: &mut Vec<VolumeInfo>,
) -> VkResult<Option<Image>> {
    if settings.paper {
        return Ok(None);
    }
    beside_directional_image(ctx, grid, face_bytes, what, info).map(Some)
}

/// One RGBA16F volume of the directional volumes' size and levels, listed in `info`.
fn beside_directional_image(
    ctx: &Arc<Context>,
    grid: VoxelGrid,
    face_bytes: u64,
    what: &str,
    info: &mut Vec<VolumeInfo>,
) -> VkResult<Image> {
    let (m, levels) = (grid.aniso_resolution(), grid.mip_levels());
    let desc = ImageDesc::d3(vk::Format::R16G16B16A16_SFLOAT, m, volume_usage()).mips(levels);
    info.push(VolumeInfo {
        name: format!("directional {what}, {m}^3 with {levels} mips"),
        bytes: face_bytes,
    });
    Image::new(ctx, &format!("directional {what}"), desc)
}

/// The thin walls' two volumes beside the directional volumes (`Volumes::thin_walls`), or
/// one-texel stand-ins without a bounce (the mip passes keep their bindings and skip them).
fn thin_wall_volumes(
    ctx: &Arc<Context>,
    grid: VoxelGrid,
    settings: &GiSettings,
    face_bytes: u64,
    info: &mut Vec<VolumeInfo>,
) -> VkResult<Option<[Image; 2]>> {
    if settings.paper {
        return Ok(None);
    }
    let make = |what: &str, info: &mut Vec<VolumeInfo>| {
        if settings.bounces >= 2 {
            beside_directional_image(ctx, grid, face_bytes, what, info)
        } else {
            let desc = ImageDesc::d3(vk::Format::R16G16B16A16_SFLOAT, 1, volume_usage());
            Image::new(ctx, &format!("directional {what} (stand-in)"), desc)
        }
    };
    Ok(Some([
        make("thin walls x y", info)?,
        make("thin walls z", info)?,
    ]))
}

/// Linear within a level, between levels as `mipmap_mode` says; transparent black beyond the
/// grid (--paper: the edge texels, as the original's clamp to edge).
fn volume_sampler(
    ctx: &Arc<Context>,
    paper: bool,
    mipmap_mode: vk::SamplerMipmapMode,
) -> VkResult<Sampler> {
    let beyond = if paper {
        vk::SamplerAddressMode::CLAMP_TO_EDGE
    } else {
        vk::SamplerAddressMode::CLAMP_TO_BORDER
    };
    Sampler::new(
        ctx,
        &vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(mipmap_mode)
            .address_mode_u(beyond)
            .address_mode_v(beyond)
            .address_mode_w(beyond)
            .border_color(vk::BorderColor::FLOAT_TRANSPARENT_BLACK)
            .max_lod(vk::LOD_CLAMP_NONE),
    )
}

/// The empty-space cells' distances (R32UI; None for --paper, a one-texel stand-in, never read,
/// when cones do not skip).
fn empty_space_volume(
    ctx: &Arc<Context>,
    grid: VoxelGrid,
    settings: &GiSettings,
    info: &mut Vec<VolumeInfo>,
) -> VkResult<Option<Image>> {
    if settings.paper {
        return Ok(None);
    }
    let side = if settings.empty_space {
        grid.empty_space_resolution()
    } else {
        1
    };
    let desc = ImageDesc::d3(
        vk::Format::R32_UINT,
        side,
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
    );
    if settings.empty_space {
        info.push(VolumeInfo {
            name: format!(
                "empty space, {side}^3 cells of {} voxels (R32UI)",
                grid.empty_space_cell()
            ),
            bytes: (side as u64).pow(3) * 4,
        });
    }
    Image::new(ctx, "empty space", desc).map(Some)
}

/// Refuses a grid before anything is allocated: the largest single allocation and the largest
/// 3D image set the largest grid.
fn check_grid_fits(ctx: &Context, grid: VoxelGrid, settings: &GiSettings) -> VkResult<()> {
    let n = grid.resolution;
    let voxels = (n as u64).pow(3);
    // Checked before allocating anything: the largest single allocation and the largest 3D
    // image set the largest grid. The widest per-voxel volume: the count and albedo sums
    // (ties with the normal and emission sums; twice the radiance's RGBA16F), or for
    // --paper one word (as wide as its RGBA8 radiance).
    // And the shaders index a buffer's words with 32-bit signed integers (SPIR-V access
    // chains): 2^31 words, 8 GiB, wherever a device allocates more.
    let limit = ctx.max_allocation.min(1 << 33);
    let (widest, texel) = if settings.paper {
        ("voxel albedo (r32ui image)", 4)
    } else {
        ("static voxel counts and albedo sums", ALBEDO_STRIDE * 4)
    };
    let max_side = ctx.properties.limits.max_image_dimension3_d;
    if voxels * texel > limit || n > max_side {
        let largest = (1..=n.min(max_side))
            .rev()
            .find(|&k| (k as u64).pow(3) * texel <= limit)
            .unwrap_or(1);
        return Err(VkError::GridTooLarge {
            grid: n,
            what: widest.into(),
            bytes: voxels * texel,
            limit,
            max_side,
            largest,
        });
    }
    Ok(())
}

/// The paper's averages are written as words (atomics need a one-channel format) and read as
/// the RGBA8 texels those words are.
const PAPER_WORDS: vk::Format = vk::Format::R32_UINT;
const PAPER_TEXELS: vk::Format = vk::Format::R8G8B8A8_UNORM;

/// The original's volumes: r32ui averages and R8 flags, one texel where unused.
fn paper_volumes(
    ctx: &Arc<Context>,
    n: u32,
    emissive: bool,
    dynamic: bool,
    info: &mut Vec<VolumeInfo>,
) -> VkResult<PaperVolumes> {
    // TRANSFER: the static pass clears them, the debug readback copies them.
    let usage = vk::ImageUsageFlags::STORAGE
        | vk::ImageUsageFlags::TRANSFER_DST
        | vk::ImageUsageFlags::TRANSFER_SRC;
    let mut volume = |name: &str, format: vk::Format, texel: u64, used: bool| -> VkResult<Image> {
        let side = if used { n } else { 1 };
        if used {
            info.push(VolumeInfo {
                name: format!("{name} ({format:?})"),
                bytes: (n as u64).pow(3) * texel,
            });
        }
        let name = if used {
            name.to_string()
        } else {
            format!("{name} (unused)")
        };
        let mut desc = ImageDesc::d3(format, side, usage);
        if format == PAPER_WORDS {
            desc.flags = vk::ImageCreateFlags::MUTABLE_FORMAT;
        }
        let mut image = Image::new(ctx, &name, desc)?;
        if format == PAPER_WORDS {
            image.view_as(PAPER_TEXELS)?;
        }
        Ok(image)
    };
    Ok(PaperVolumes {
        albedo: volume("voxel albedo", PAPER_WORDS, 4, true)?,
        normal: volume("voxel normal", PAPER_WORDS, 4, true)?,
        emission: volume("voxel emission", PAPER_WORDS, 4, emissive)?,
        flag: volume("static flags", vk::Format::R8_UNORM, 1, dynamic)?,
        emissive,
        dynamic,
    })
}

/// Voxelization's accumulators: the original's RGBA8 averages, or the default's fixed-point sums
/// (static, and dynamic when nodes move).
fn voxel_data(
    ctx: &Arc<Context>,
    grid: VoxelGrid,
    settings: &GiSettings,
    emissive: bool,
    dynamic: bool,
    info: &mut Vec<VolumeInfo>,
) -> VkResult<VoxelData> {
    let voxels = (grid.resolution as u64).pow(3);
    // TRANSFER_SRC: the debug readback copies them.
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER
        | vk::BufferUsageFlags::TRANSFER_DST
        | vk::BufferUsageFlags::TRANSFER_SRC
        | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
    let mut buffer = |name: &str, stride: u64| -> VkResult<Buffer> {
        info.push(VolumeInfo {
            name: name.into(),
            bytes: voxels * stride * 4,
        });
        Buffer::new(
            ctx,
            name,
            voxels * stride * 4,
            storage,
            MemoryLocation::GpuOnly,
        )
    };
    let data = if settings.paper {
        VoxelData::Paper(paper_volumes(
            ctx,
            grid.resolution,
            emissive,
            dynamic,
            info,
        )?)
    } else {
        let mut sums = |pass: &str| -> VkResult<Sums> {
            Ok(Sums {
                albedo: buffer(
                    &format!("{pass} voxel counts and albedo sums"),
                    ALBEDO_STRIDE,
                )?,
                normal: buffer(&format!("{pass} voxel normal sums"), NORMAL_STRIDE)?,
                spread: buffer(
                    &format!("{pass} voxel squared normal and glossy sums"),
                    SPREAD_STRIDE,
                )?,
                emission: emissive
                    .then(|| buffer(&format!("{pass} emission sums"), EMISSION_STRIDE))
                    .transpose()?,
            })
        };
        VoxelData::Sums {
            static_sums: sums("static")?,
            dynamic_sums: dynamic.then(|| sums("dynamic").map(Box::new)).transpose()?,
        }
    };
    Ok(data)
}
