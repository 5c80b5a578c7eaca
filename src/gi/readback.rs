//! Debug readback of the volumes: what voxelization and injection wrote, decoded on the CPU the
//! way the shaders decode it (glsl/voxel_data.glsl), for tests and numerical checks.

use super::volumes::{VoxelData, ALBEDO_STRIDE, EMISSION_STRIDE, NORMAL_STRIDE, SPREAD_STRIDE};
use super::Gi;
use crate::vk::{vk, Access, Buffer, Context, Graph, Image, ResourceStates, VkResult};
use glam::{Vec3, Vec4};
use std::sync::Arc;

/// Every voxel, x fastest then y then z.
#[derive(Clone, Debug)]
pub struct VoxelDump {
    pub resolution: u32,
    pub filled: Vec<bool>,
    /// Fragments averaged into each voxel (default mode; the 8-bit count for --paper).
    pub count: Vec<u32>,
    pub albedo: Vec<Vec3>,
    /// The share of the albedo's light that a mirror-like lobe sends one way (default mode;
    /// glsl/voxel_data.glsl's `Voxel::glossy`): the lit voxels hold it in the glossy volume,
    /// not in `radiance`.
    pub glossy: Vec<f32>,
    /// The averaged normal (not normalized: its length is how much the normals agree).
    pub normal: Vec<Vec3>,
    pub emission: Vec<Vec3>,
    /// Outgoing radiance (the full-resolution volume's and the glossy lobes') and opacity, when
    /// the voxels are lit.
    pub radiance: Option<Vec<Vec4>>,
    /// When the voxels are lit: every texel of every level of the directional volumes and of
    /// the volumes beside them (light direction and position; none for --paper, whose texels
    /// are RGBA8), in the order of `Volumes::directional`, level by level; as stored (radiance
    /// times the radiance scale).
    pub directional: Option<Vec<Vec4>>,
    /// When the voxels are lit and the scene emits (default mode): the emission of emitters
    /// smaller than their voxel, as stored.
    pub small_emission: Option<Vec<f32>>,
    /// When the voxels are lit and hold their backs' light (`GiSettings::backs`): each voxel's
    /// back's outgoing radiance (zero but for open backs).
    pub back_radiance: Option<Vec<Vec3>>,
    /// When the voxels are lit and cones skip empty space: per cell of `empty_space_cell`
    /// voxels a side (x fastest), its distance in cells to the nearest filled cell.
    pub empty_space: Option<Vec<u32>>,
    pub empty_space_cell: u32,
}

impl VoxelDump {
    /// An empty grid of side n, nothing lit: what the decoders fill.
    fn empty(n: u32) -> VoxelDump {
        let nv = (n as usize).pow(3);
        VoxelDump {
            resolution: n,
            filled: vec![false; nv],
            count: vec![0; nv],
            albedo: vec![Vec3::ZERO; nv],
            glossy: vec![0.0; nv],
            normal: vec![Vec3::ZERO; nv],
            emission: vec![Vec3::ZERO; nv],
            radiance: None,
            directional: None,
            small_emission: None,
            back_radiance: None,
            empty_space: None,
            empty_space_cell: 0,
        }
    }

    pub fn index(&self, x: u32, y: u32, z: u32) -> usize {
        let n = self.resolution as usize;
        x as usize + n * (y as usize + n * z as usize)
    }
}

fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let man = (h & 0x3ff) as f32;
    match exp {
        0 => sign * man * 2f32.powi(-24),
        31 => {
            if man == 0.0 {
                sign * f32::INFINITY
            } else {
                f32::NAN
            }
        }
        e => sign * (1.0 + man / 1024.0) * 2f32.powi(e - 15),
    }
}

fn unpack_rgba8(v: u32) -> Vec4 {
    Vec4::new(
        (v & 0xff) as f32,
        ((v >> 8) & 0xff) as f32,
        ((v >> 16) & 0xff) as f32,
        ((v >> 24) & 0xff) as f32,
    )
}

fn words(bytes: &[u8]) -> Vec<u32> {
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Records the copy of one mip level (a cube of `side` texels) of a 3D image, in
/// TRANSFER_SRC_OPTIMAL, to `host` at `offset`.
///
/// # Safety
/// `cmd` is recording.
unsafe fn copy_level(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    img: &Image,
    level: u32,
    side: u32,
    host: &Buffer,
    offset: u64,
) {
    ctx.device.cmd_copy_image_to_buffer(
        cmd,
        img.raw,
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        host.raw,
        &[crate::vk::level_copy(
            offset,
            level,
            vk::Extent3D {
                width: side,
                height: side,
                depth: side,
            },
        )],
    )
}

/// Which lit volume a level belongs to.
enum Lit {
    Radiance,
    /// In the order of `Volumes::directional`.
    Directional(usize),
    SmallEmission,
    BackRadiance,
    GlossyRadiance,
}

/// One mip level of a lit volume, as the readbacks copy it.
struct LitLevel<'a> {
    img: &'a Image,
    /// Bytes a texel.
    texel: u64,
    level: u32,
    side: u32,
    kind: Lit,
}

impl Gi {
    /// The lit volumes' levels, none before the voxels are lit: the radiance, then every level
    /// of the directional volumes and of those beside them (--paper: RGBA8, and none beside
    /// them), and the small emitters' volume when the scene emits (without emitters it is a
    /// one-texel stand-in).
    fn lit_levels(&self) -> Vec<LitLevel<'_>> {
        let mut levels = Vec::new();
        if self.lighting.is_none() {
            return levels;
        }
        let n = self.volumes.grid.resolution;
        let texel = if self.settings.paper { 4 } else { 8 };
        levels.push(LitLevel {
            img: &self.volumes.radiance,
            texel,
            level: 0,
            side: n,
            kind: Lit::Radiance,
        });
        for (i, img) in self.volumes.directional().enumerate() {
            let side = img.desc.extent.width;
            for level in 0..img.desc.mip_levels {
                levels.push(LitLevel {
                    img,
                    texel,
                    level,
                    side: (side >> level).max(1),
                    kind: Lit::Directional(i),
                });
            }
        }
        if let (Some(small), true) = (&self.volumes.small_emission, self.emissive) {
            levels.push(LitLevel {
                img: small,
                texel: 4,
                level: 0,
                side: n,
                kind: Lit::SmallEmission,
            });
        }
        if let (Some(back), true) = (&self.volumes.back_radiance, self.volumes.holds_backs()) {
            levels.push(LitLevel {
                img: back,
                texel: 8,
                level: 0,
                side: n,
                kind: Lit::BackRadiance,
            });
        }
        if let Some(glossy) = &self.volumes.glossy_radiance {
            levels.push(LitLevel {
                img: glossy,
                texel: 8,
                level: 0,
                side: n,
                kind: Lit::GlossyRadiance,
            });
        }
        levels
    }

    /// Copies the volumes to host memory and decodes them. Waits for the GPU.
    pub fn read_voxels(
        &self,
        ctx: &Arc<Context>,
        states: &mut ResourceStates,
    ) -> VkResult<VoxelDump> {
        let (sources, directional_names) = self.readback_sources();
        let (host, ranges) = copy_to_host(ctx, states, &sources)?;
        let bytes = host.mapped().expect("readback is host-visible");
        let parts: Parts = sources
            .iter()
            .zip(&ranges)
            .map(|((name, _), &(offset, size))| {
                (
                    name.as_str(),
                    &bytes[offset as usize..(offset + size) as usize],
                )
            })
            .collect();
        let mut dump = VoxelDump::empty(self.volumes.grid.resolution);
        self.decode_sums(&parts, &mut dump);
        decode_paper(&parts, &mut dump);
        self.decode_lit(&parts, &directional_names, &mut dump);
        Ok(dump)
    }

    /// What the readback copies, by name, in a fixed order: the accumulation buffers (static
    /// and dynamic sums, or --paper's RGBA8 averages), then the lit volumes' levels; and the
    /// names of the directional levels, in order.
    fn readback_sources(&self) -> (Vec<(String, Src<'_>)>, Vec<String>) {
        let mut sources: Vec<(String, Src)> = Vec::new();
        let mut directional_names = Vec::new();
        match &self.volumes.data {
            VoxelData::Sums {
                static_sums,
                dynamic_sums,
            } => {
                // Of the spread words only the glossy part is decoded, not the squared normals.
                let passes = [
                    (["sa", "sn", "ss", "se"], Some(static_sums)),
                    (["da", "dn", "ds", "de"], dynamic_sums.as_deref()),
                ];
                for ([a, n, s, e], sums) in passes {
                    let Some(sums) = sums else { continue };
                    sources.push((a.into(), Src::Buf(&sums.albedo)));
                    sources.push((n.into(), Src::Buf(&sums.normal)));
                    sources.push((s.into(), Src::Buf(&sums.spread)));
                    if let Some(b) = &sums.emission {
                        sources.push((e.into(), Src::Buf(b)));
                    }
                }
            }
            VoxelData::Paper(p) => {
                let n = self.volumes.grid.resolution;
                sources.push(("pa".into(), Src::Img(&p.albedo, 4, 0, n)));
                sources.push(("pn".into(), Src::Img(&p.normal, 4, 0, n)));
                if p.emissive {
                    sources.push(("pe".into(), Src::Img(&p.emission, 4, 0, n)));
                }
            }
        }
        for l in self.lit_levels() {
            let name = match l.kind {
                Lit::Radiance => "r".to_string(),
                Lit::Directional(i) => {
                    let name = format!("directional {i} level {}", l.level);
                    directional_names.push(name.clone());
                    name
                }
                Lit::SmallEmission => "small".to_string(),
                Lit::BackRadiance => "back".to_string(),
                Lit::GlossyRadiance => "glossy".to_string(),
            };
            sources.push((name, Src::Img(l.img, l.texel, l.level, l.side)));
        }
        if let (Some(_), Some(img)) = (&self.empty_space, &self.volumes.empty_space) {
            let side = self.volumes.grid.empty_space_resolution();
            sources.push(("empty".into(), Src::Img(img, 4, 0, side)));
        }
        (sources, directional_names)
    }

    /// The default voxels: static plus dynamic fixed-point sums, divided by their count.
    fn decode_sums(&self, parts: &Parts, dump: &mut VoxelDump) {
        let (Some(sa), Some(sn)) = (parts.get("sa"), parts.get("sn")) else {
            return;
        };
        let (sa, sn) = (words(sa), words(sn));
        let da = parts.get("da").map(|b| words(b));
        let dn = parts.get("dn").map(|b| words(b));
        let ss = parts.get("ss").map(|b| words(b));
        let ds = parts.get("ds").map(|b| words(b));
        let se = parts.get("se").map(|b| words(b));
        let de = parts.get("de").map(|b| words(b));
        let (sa_stride, sn_stride) = (ALBEDO_STRIDE as usize, NORMAL_STRIDE as usize);
        let es = EMISSION_STRIDE as usize;
        for v in 0..dump.filled.len() {
            // The words in the order of glsl/voxel_common.glsl: count, albedo, normal, where
            // the surfaces lie.
            let mut w: Vec<u32> = sa[v * sa_stride..(v + 1) * sa_stride]
                .iter()
                .chain(&sn[v * sn_stride..(v + 1) * sn_stride])
                .copied()
                .collect();
            if let (Some(da), Some(dn)) = (&da, &dn) {
                let d = da[v * sa_stride..(v + 1) * sa_stride]
                    .iter()
                    .chain(&dn[v * sn_stride..(v + 1) * sn_stride]);
                for (a, b) in w.iter_mut().zip(d) {
                    *a = a.wrapping_add(*b);
                }
            }
            let count = w[0];
            dump.count[v] = count;
            dump.filled[v] = count > 0;
            if count == 0 {
                continue;
            }
            let inv = 1.0 / (count as f32 * 4096.0);
            let albedo = Vec3::new(w[1] as f32, w[2] as f32, w[3] as f32) * inv;
            dump.albedo[v] = albedo;
            let reflected = crate::output::luminance(albedo);
            // The glossy part's luminance: the last spread word.
            let spread = SPREAD_STRIDE as usize;
            let glossy = |s: &Option<Vec<u32>>| s.as_ref().map_or(0, |s| s[(v + 1) * spread - 1]);
            let g = glossy(&ss).wrapping_add(glossy(&ds));
            if reflected > 0.0 {
                dump.glossy[v] = (g as f32 * inv / reflected).clamp(0.0, 1.0);
            }
            dump.normal[v] =
                Vec3::new(w[4] as i32 as f32, w[5] as i32 as f32, w[6] as i32 as f32) * inv;
            if let Some(se) = &se {
                let mut e = [se[v * es], se[v * es + 1], se[v * es + 2], se[v * es + 3]];
                if let Some(de) = &de {
                    for k in 0..4 {
                        e[k] = e[k].wrapping_add(de[v * es + k]);
                    }
                }
                let coverage = (e[3] as f32 / 4096.0).max(1.0);
                dump.emission[v] = Vec3::new(e[0] as f32, e[1] as f32, e[2] as f32)
                    / (coverage * self.emission_scale);
            }
        }
    }

    /// The lit volumes: radiance (back from its scale), the directional levels and the small
    /// emission volume.
    fn decode_lit(&self, parts: &Parts, directional_names: &[String], dump: &mut VoxelDump) {
        let directional: Vec<Vec4> = directional_names
            .iter()
            .flat_map(|name| {
                let bytes = parts[name.as_str()];
                if self.settings.paper {
                    words(bytes)
                        .into_iter()
                        .map(|w| unpack_rgba8(w) / 255.0)
                        .collect()
                } else {
                    halves(bytes)
                }
            })
            .collect();
        if !directional.is_empty() {
            dump.directional = Some(directional);
        }
        dump.empty_space = parts.get("empty").map(|b| words(b));
        dump.empty_space_cell = self.volumes.grid.empty_space_cell();
        dump.small_emission = parts.get("small").map(|b| {
            b.chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect()
        });
        // Back to radiance: the volumes hold it times the radiance scale.
        let k = self.radiance_scale;
        dump.back_radiance = parts
            .get("back")
            .map(|b| halves(b).into_iter().map(|t| t.truncate() / k).collect());
        if let Some(r) = parts.get("r") {
            let texels: Vec<Vec4> = if self.settings.paper {
                words(r)
                    .into_iter()
                    .map(|w| unpack_rgba8(w) / 255.0)
                    .collect()
            } else {
                halves(r)
            };
            // The light of mirror-like lobes lies in a volume of its own (Volumes::glossy_radiance).
            let glossy = parts.get("glossy").map(|g| halves(g));
            dump.radiance = Some(
                texels
                    .into_iter()
                    .enumerate()
                    .map(|(i, t)| {
                        let g = glossy.as_ref().map_or(Vec4::ZERO, |g| g[i]);
                        ((t + g).truncate() / k).extend(t.w)
                    })
                    .collect(),
            );
        }
    }
}

/// A readback source: a buffer, or one mip level of an image (bytes per texel, level, side).
enum Src<'a> {
    Buf(&'a Buffer),
    Img(&'a Image, u64, u32, u32),
}

/// The copied bytes of each source, by name.
type Parts<'a> = std::collections::HashMap<&'a str, &'a [u8]>;

/// Copies the sources into one host-visible buffer, each part 16-byte aligned (an image's copy
/// must start at a multiple of its texel size, and a grid of odd size leaves the buffers before
/// it a multiple of 4 only). Returns the buffer and each part's offset and size. Waits.
fn copy_to_host(
    ctx: &Arc<Context>,
    states: &mut ResourceStates,
    sources: &[(String, Src)],
) -> VkResult<(Buffer, Vec<(u64, u64)>)> {
    let ranges: Vec<(u64, u64)> = sources
        .iter()
        .map(|(_, s)| match s {
            Src::Buf(b) => b.size,
            Src::Img(_, t, _, side) => (*side as u64).pow(3) * t,
        })
        .scan(0u64, |end, size| {
            let start = end.next_multiple_of(16);
            *end = start + size;
            Some((start, size))
        })
        .collect();
    let total = ranges.last().map_or(0, |(o, s)| o + s);
    let host = Buffer::readback(ctx, "voxel readback", total)?;
    ctx.one_shot(|cmd| {
        let mut g = Graph::new(ctx, cmd, states, None);
        let mut pass = g
            .pass("voxel readback")
            .buffer(&host, Access::TransferWrite);
        for (_, s) in sources {
            pass = match s {
                Src::Buf(b) => pass.buffer(b, Access::TransferRead),
                Src::Img(i, ..) => pass.image(i, Access::TransferRead),
            };
        }
        pass.record(|cmd| unsafe {
            for ((_, s), &(offset, size)) in sources.iter().zip(&ranges) {
                match s {
                    Src::Buf(b) => ctx.device.cmd_copy_buffer(
                        cmd,
                        b.raw,
                        host.raw,
                        &[vk::BufferCopy {
                            src_offset: 0,
                            dst_offset: offset,
                            size,
                        }],
                    ),
                    Src::Img(i, _, level, side) => {
                        copy_level(ctx, cmd, i, *level, *side, &host, offset)
                    }
                }
            }
        });
        g.barrier("voxel readback to host")
            .buffer(&host, Access::HostRead)
            .record(|_| {});
    })?;
    states.forget(host.raw);
    Ok((host, ranges))
}

/// --paper's voxels: RGBA8 averages (albedo with the count in alpha, normal, emission).
fn decode_paper(parts: &Parts, dump: &mut VoxelDump) {
    let (Some(pa), Some(pn)) = (parts.get("pa"), parts.get("pn")) else {
        return;
    };
    let (pa, pn) = (words(pa), words(pn));
    let pe = parts.get("pe").map(|b| words(b));
    for v in 0..dump.filled.len() {
        let a = unpack_rgba8(pa[v]);
        dump.count[v] = a.w as u32;
        dump.filled[v] = a.w > 0.0;
        dump.albedo[v] = a.truncate() / 255.0;
        dump.normal[v] = unpack_rgba8(pn[v]).truncate() / 255.0 * 2.0 - Vec3::ONE;
        if let Some(pe) = &pe {
            dump.emission[v] = unpack_rgba8(pe[v]).truncate() / 255.0;
        }
    }
}

/// RGBA16F texels.
fn halves(b: &[u8]) -> Vec<Vec4> {
    b.chunks_exact(8)
        .map(|c| {
            let h = |i: usize| f16_to_f32(u16::from_le_bytes([c[i], c[i + 1]]));
            Vec4::new(h(0), h(2), h(4), h(6))
        })
        .collect()
}

/// Texels of `bytes` (RGBA16F when `texel` is 8, R32F when 4) with a non-finite component.
fn non_finite_texels(bytes: &[u8], texel: u64) -> usize {
    if texel == 8 {
        // Four half floats a texel; an exponent of all ones is Inf or NaN.
        bytes
            .chunks_exact(8)
            .filter(|t| {
                t.chunks_exact(2)
                    .any(|h| u16::from_le_bytes([h[0], h[1]]) & 0x7c00 == 0x7c00)
            })
            .count()
    } else {
        bytes
            .chunks_exact(4)
            .filter(|f| !f32::from_le_bytes([f[0], f[1], f[2], f[3]]).is_finite())
            .count()
    }
}

/// Non-finite values in the volumes, by kind, from `Gi::count_non_finite`.
#[derive(Clone, Debug, Default)]
pub struct NonFinite {
    /// Voxels of the radiance volume.
    pub radiance: usize,
    /// Texels of the directional volumes and of the volumes beside them, every level.
    pub directional: usize,
    /// Voxels of the small emitters' volume.
    pub small_emission: usize,
    /// Voxels of the backs' radiance volume.
    pub back_radiance: usize,
    /// Voxels of the glossy lobes' radiance volume.
    pub glossy_radiance: usize,
}

impl NonFinite {
    pub fn total(&self) -> usize {
        self.radiance
            + self.directional
            + self.small_emission
            + self.back_radiance
            + self.glossy_radiance
    }
}

impl Gi {
    /// Counts non-finite values in the lit volumes, one mip level at a time, so that a 512^3
    /// grid needs no more host memory than its largest level (`read_voxels` holds every
    /// volume, decoded, at once). Voxelization's words are integers (sums, counts, RGBA8) and
    /// decode to finite values; the paper's volumes are all RGBA8. Waits for the GPU.
    pub fn count_non_finite(
        &self,
        ctx: &Arc<Context>,
        states: &mut ResourceStates,
    ) -> VkResult<NonFinite> {
        let mut found = NonFinite::default();
        if self.lighting.is_none() || self.settings.paper {
            return Ok(found);
        }
        let levels = self.lit_levels();
        let largest = levels
            .iter()
            .map(|l| (l.side as u64).pow(3) * l.texel)
            .max()
            .unwrap_or(4);
        let host = Buffer::readback(ctx, "non-finite readback", largest)?;
        for l in levels {
            let (img, level, side) = (l.img, l.level, l.side);
            ctx.one_shot(|cmd| {
                let mut g = Graph::new(ctx, cmd, states, None);
                g.pass("non-finite readback")
                    .buffer(&host, Access::TransferWrite)
                    .image(img, Access::TransferRead)
                    .record(|cmd| unsafe { copy_level(ctx, cmd, img, level, side, &host, 0) });
                g.barrier("non-finite readback to host")
                    .buffer(&host, Access::HostRead)
                    .record(|_| {});
            })?;
            let bytes = host.mapped().expect("readback is host-visible");
            let bytes = &bytes[..((side as u64).pow(3) * l.texel) as usize];
            let bad = non_finite_texels(bytes, l.texel);
            match l.kind {
                Lit::Radiance => found.radiance += bad,
                Lit::Directional(_) => found.directional += bad,
                Lit::SmallEmission => found.small_emission += bad,
                Lit::BackRadiance => found.back_radiance += bad,
                Lit::GlossyRadiance => found.glossy_radiance += bad,
            }
        }
        states.forget(host.raw);
        Ok(found)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn half_floats_decode() {
        assert_eq!(super::f16_to_f32(0x3c00), 1.0);
        assert_eq!(super::f16_to_f32(0x4c40), 17.0);
        assert_eq!(super::f16_to_f32(0xc000), -2.0);
        assert!(super::f16_to_f32(0x7e00).is_nan());
    }

    #[test]
    fn non_finite_texels_are_counted_once_each() {
        // RGBA16F: 1.0 everywhere, then NaN in one channel, +Inf and -Inf in two channels of
        // another texel, and the largest finite half (exponent 30) in a fourth.
        let half = |h: [u16; 4]| h.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
        let one = 0x3c00;
        let texels = [
            half([one; 4]),
            half([one, 0x7e00, one, one]),
            half([0x7c00, one, 0xfc00, one]),
            half([0x7bff, one, one, one]),
        ]
        .concat();
        assert_eq!(super::non_finite_texels(&texels, 8), 2);
        // R32F: NaN, Inf, 0, the largest finite float.
        let floats: Vec<u8> = [f32::NAN, f32::INFINITY, 0.0, f32::MAX]
            .iter()
            .flat_map(|f| f.to_le_bytes())
            .collect();
        assert_eq!(super::non_finite_texels(&floats, 4), 2);
    }
}
