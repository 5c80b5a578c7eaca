//! Deferred voxel shading (Villegas and Ramirez 2016), the four steps and the second bounce:
//! `voxelize` (scene to voxels), `inject` (direct light per voxel), `mip` (six directional
//! volumes), `bounce` (a second bounce), `trace` (cones per pixel, and the debug views).

mod bounce;
mod empty_space;
mod inject;
mod mip;
mod readback;
mod trace;
mod volumes;
mod voxelize;

pub use readback::{NonFinite, VoxelDump};
pub use volumes::{VolumeInfo, Volumes, BOUNCE_BLOCK};

use crate::scene::Aabb;
use crate::vk::{vk, Access, Buffer, Context, Graph, Pipeline, SharedSet, VertexLayout, VkResult};
use glam::{Vec3, Vec4};
use std::ops::Range;
use std::sync::Arc;

pub use bounce::{list_capacity, Bounce};
pub use empty_space::EmptySpace;
pub use inject::{Inject, ShadowMapsIn};
pub use mip::Mip;
pub use trace::{FrameImages, Trace, TraceFrame, TraceLayout, TraceMode, GBUFFER_NAMES};
pub use voxelize::{Voxelizer, EMITTER_LIGHT};

/// The most light bounces `GiSettings::bounces` may ask for.
pub const MAX_BOUNCES: u32 = 8;

/// Settings of the voxel passes. `Default` is the project's default; `paper()` the original's.
#[derive(Clone, Debug, PartialEq)]
pub struct GiSettings {
    /// Voxels per side of the grid.
    pub voxels: u32,
    /// 1: direct light in the voxels only; N >= 2: plus N - 1 bounces between voxels (each
    /// gathers from the volumes the previous one left, up to [`MAX_BOUNCES`]).
    pub bounces: u32,
    /// Reproduce the original's behaviour and constants.
    pub paper: bool,
    /// Diffuse cones per pixel (1 to 16).
    pub cone_count: u32,
    /// Full aperture of each diffuse cone, in degrees.
    pub cone_aperture_deg: f32,
    /// Diffuse cones per voxel in the bounces (1 to 16; not `paper`, whose propagation has its
    /// own four).
    pub bounce_cone_count: u32,
    /// Full aperture of each of the bounces' cones, in degrees.
    pub bounce_cone_aperture_deg: f32,
    /// Step length as a fraction of the cone diameter.
    pub step_factor: f32,
    /// Longest cone, as a fraction of the grid's edge (cones also end a diameter past the grid).
    pub max_distance: f32,
    /// How far cones start off the surface, in voxels.
    pub start_offset: f32,
    /// AO falloff per voxel of diameter (occlusion / (1 + falloff x diameter in voxels)).
    /// `paper` uses the original's instead, 0.5 x [`PAPER_AO_FALLOFF`] / the grid's edge per metre.
    pub ao_falloff: f32,
    /// Voxel visibility by tracing the voxels instead of the shadow maps.
    pub voxel_shadows: bool,
    /// Pixels' direct light shadowed by a cone through the voxels instead of the shadow maps.
    pub cone_shadows: bool,
    /// With `paper`: the original's slips reproduced where cheap (docs/porting.md): the -X
    /// directional volume bound to all six of the light pass's units, and a winding flip that
    /// swaps two corners' texture coordinates but not their normals.
    pub paper_slips: bool,
    /// Mip levels finer than the cone's diameter at which cones sample (the paper: 1).
    pub lod_offset: f32,
    /// The last bounce also adds the bounces after it, as a geometric series whose ratio is
    /// the voxels' albedo times their closed share, their mean weighted by the light each
    /// gathered, at most 0.8 (glsl/bounce_tail.comp has the details).
    /// Needs `bounces` >= 2; not for `paper`.
    pub tail: bool,
    /// Emissive surfaces light the scene as area lights, integrated per pixel, with soft
    /// shadows (src/render/area_lights.rs), instead of as voxel emission. Not for `paper`.
    pub area_lights: bool,
    /// Pixels per side of the blocks that trace the diffuse cones once (1, 2 or 4), their
    /// result upsampled by position and normal (glsl/diffuse_gather.comp). Not for `paper`.
    pub trace_scale: u32,
    /// Frames over which the diffuse cones are traced (0: all in every frame): each frame
    /// traces every N-th cone and adds it to a history reprojected from the frame before.
    /// Not for `paper`.
    pub temporal: u32,
    /// The specular cone's narrowest diameter, in voxels. A step is half the diameter, so a
    /// near-mirror's cone (a tangent of 0.02) steps half a voxel at a time for its first 25
    /// voxels with 1, and a voxel at a time for its first 50 with 2; each sample reads the
    /// full-resolution voxels within a voxel and a half (filtered by hand), so samples a voxel
    /// apart still overlap. Not for `paper` (its cones have no such floor).
    pub specular_min_voxels: f32,
    /// Cones jump across empty space: a volume of cells, each with its distance to the nearest
    /// filled one (src/gi/empty_space.rs), lets a cone skip the samples that could read
    /// nothing. Not for `paper`.
    pub empty_space: bool,
    /// A voxel of a surface facing one way with open space behind it (a zero-thickness wall,
    /// a quad; empty voxels for half the grid) holds the light its back reflects apart, in a second radiance volume: lit
    /// directly, gathering its own side in the bounces, and seen by cones from behind only
    /// (glsl/voxel_data.glsl, `open_back`). Not for `paper`, whose voxels shine every way.
    pub backs: bool,
    /// One-sided voxels share their bounce gather within blocks of [`BOUNCE_BLOCK`]^3: where
    /// nothing rises in front of the plane of a block's first one-sided voxel, one gather from
    /// the middle of that plane, which the block's voxels in it facing within 26 degrees of it
    /// take (glsl/inject_bounce.comp). Not for `paper`.
    pub bounce_share: bool,
}

impl Default for GiSettings {
    fn default() -> Self {
        GiSettings {
            // From the Pareto fronts of docs/defaults.md: 128^3 is no more
            // accurate than 64^3 for three times the time. The second bounce gains or holds on
            // every bench scene and the closed rooms of docs/hard-cases.md need it; it runs
            // only when a light or a node moves (a still frame only traces).
            voxels: 64,
            bounces: 2,
            paper: false,
            // 16 narrow cones instead of the paper's 6 of 60 degrees: wide cones' samples reach
            // back into the surface they leave (opaque and, seen from behind, dark), and six
            // cones are a coarse quadrature near small bright emitters (docs/hard-cases.md).
            cone_count: 16,
            cone_aperture_deg: 36.0,
            // The bounces' cones: 12 of the pixels' 36 degrees. A voxel's bounce light reaches
            // the image through the pixels' cones, which blur it: 16 cost the frame after a
            // light moves a fifth more for the same error; fewer and wider ones cost closed
            // rooms' light (docs/hard-cases.md).
            bounce_cone_count: 12,
            bounce_cone_aperture_deg: 36.0,
            step_factor: 0.5,
            // Cones end where the grid does (a diameter past its edge), not before: the paper's
            // 0.95 of the edge cut off cones across a closed room before its far walls made
            // them opaque, losing up to 16% of the light by where those walls fell in the
            // coarse texels (docs/hard-cases.md). Twice the edge exceeds the grid's diagonal.
            max_distance: 2.0,
            start_offset: 1.0,
            ao_falloff: 1.0,
            voxel_shadows: false,
            cone_shadows: false,
            paper_slips: false,
            lod_offset: 1.0,
            // The closed rooms of docs/hard-cases.md lose a tenth of their light and more
            // without the third and later bounces; tracing them costs a bounce pass each.
            tail: true,
            // Cones sample an emitter at a few directions and coarse levels (streaks and
            // blotches); a voxel's one radiance spreads a small emitter's light over what its
            // coarse texels reach (docs/hard-cases.md, emissive-1e4, emitters).
            area_lights: true,
            // The still frame 16 times faster on CornellBox-Original at 256x256 at the same
            // relMSE (docs/fast-frames.md): diffuse cones per block of 4 x 4 (within 4e-5 relMSE
            // of every pixel's own on the bench scenes), kept over frames while the light in
            // the voxels holds, what a moving camera uncovers completed over 4 frames. Scale 4
            // rather than 2: a frame after a light moved traces every block's whole set, a
            // quarter of scale 2's cost (0.25 s at 256x256, 1 s at 512x512).
            trace_scale: 4,
            temporal: 4,
            // Half the specular cone's cost at the same relMSE on seven scenes, mirrors and
            // normal-mapped metal among them (docs/fast-frames.md, "The specular cone's floor");
            // 4 voxels blurs a near-mirror's reflection (MetalRoughSpheres 7% worse).
            specular_min_voxels: 2.0,
            // The same images (the skipped samples read nothing), the specular cone's trace
            // 1.5 to 2 times faster on open scenes (docs/fast-frames.md, "Empty space").
            empty_space: true,
            // A room of single quads facing out, open on one side under a sky: relMSE 0.072
            // without (its quads' voxels reflected only outwards), docs/environment.md.
            backs: true,
            // The frame after a light moves a third faster on CornellBox-Original (952 ->
            // 609 ms) at the same relMSE; every hard case within +0.0003, door-room lower
            // (docs/fast-frames.md, "The frame after a light moves").
            bounce_share: true,
        }
    }
}

/// The original's aoFalloff (gi_deferred_renderer.cpp): its AO divides each sample's occlusion
/// by 1 + 0.5 x 800 x diameter / the grid's edge, 400 / N per voxel of diameter.
pub const PAPER_AO_FALLOFF: f32 = 800.0;

impl GiSettings {
    /// The original's constants (PAPER_NOTES.md): 6 cones of 60 degrees, step 0.5 x diameter,
    /// 0.95 of the grid, a start 2 voxels off the surface.
    pub fn paper(voxels: u32) -> Self {
        GiSettings {
            voxels,
            paper: true,
            bounces: 2,
            cone_count: 6,
            cone_aperture_deg: 60.0,
            bounce_cone_count: 6,
            bounce_cone_aperture_deg: 60.0,
            step_factor: 0.5,
            max_distance: 0.95,
            start_offset: 2.0,
            tail: false,
            area_lights: false,
            trace_scale: 1,
            temporal: 0,
            specular_min_voxels: 1.0,
            empty_space: false,
            backs: false,
            bounce_share: false,
            ..Default::default()
        }
    }
}

/// A setting's value, by kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Count(u32),
    Real(f32),
    Switch(bool),
}

impl Value {
    pub fn as_f64(self) -> f64 {
        match self {
            Value::Count(n) => n as f64,
            Value::Real(x) => x as f64,
            Value::Switch(b) => b as u32 as f64,
        }
    }
    /// Whole numbers only (counts and switches).
    pub fn integer(self) -> bool {
        !matches!(self, Value::Real(_))
    }
    /// As a sweep's label writes it: switches as 0 or 1.
    pub fn label(self) -> String {
        match self {
            Value::Count(n) => n.to_string(),
            Value::Real(x) => x.to_string(),
            Value::Switch(b) => (b as u32).to_string(),
        }
    }
    /// As the results' columns write it: switches as true or false.
    pub fn column(self) -> String {
        match self {
            Value::Count(n) => n.to_string(),
            Value::Real(x) => x.to_string(),
            Value::Switch(b) => b.to_string(),
        }
    }
}

/// One field of [`GiSettings`] as the bench sees it: the axis a sweep varies (`--sweep
/// NAME=..`), the results' column, the range a sweep may ask for, and how to read and set it.
pub struct Field {
    pub axis: &'static str,
    pub column: &'static str,
    pub min: f64,
    pub max: f64,
    pub get: fn(&GiSettings) -> Value,
    pub set: fn(&mut GiSettings, f64),
}

/// Every field of [`GiSettings`], in order: a new setting is its field, its line here, its
/// uniform (if the shaders read it) and its command-line flag.
pub const FIELDS: &[Field] = &[
    Field {
        axis: "voxels",
        column: "voxels",
        min: 4.0,
        max: 1024.0,
        get: |g| Value::Count(g.voxels),
        set: |g, v| g.voxels = v as u32,
    },
    Field {
        axis: "bounces",
        column: "bounces",
        min: 1.0,
        max: MAX_BOUNCES as f64,
        get: |g| Value::Count(g.bounces),
        set: |g, v| g.bounces = v as u32,
    },
    Field {
        axis: "paper",
        column: "paper",
        min: 0.0,
        max: 1.0,
        get: |g| Value::Switch(g.paper),
        set: |g, v| g.paper = v != 0.0,
    },
    Field {
        axis: "cones",
        column: "cone_count",
        min: 1.0,
        max: 16.0,
        get: |g| Value::Count(g.cone_count),
        set: |g, v| g.cone_count = v as u32,
    },
    Field {
        axis: "aperture",
        column: "cone_aperture_deg",
        min: 0.5,
        max: 179.0,
        get: |g| Value::Real(g.cone_aperture_deg),
        set: |g, v| g.cone_aperture_deg = v as f32,
    },
    Field {
        axis: "bounce-cones",
        column: "bounce_cone_count",
        min: 1.0,
        max: 16.0,
        get: |g| Value::Count(g.bounce_cone_count),
        set: |g, v| g.bounce_cone_count = v as u32,
    },
    Field {
        axis: "bounce-aperture",
        column: "bounce_cone_aperture_deg",
        min: 0.5,
        max: 179.0,
        get: |g| Value::Real(g.bounce_cone_aperture_deg),
        set: |g, v| g.bounce_cone_aperture_deg = v as f32,
    },
    Field {
        axis: "step",
        column: "step_factor",
        min: 0.05,
        max: 4.0,
        get: |g| Value::Real(g.step_factor),
        set: |g, v| g.step_factor = v as f32,
    },
    Field {
        axis: "max-distance",
        column: "max_distance",
        min: 0.01,
        max: 2.0,
        get: |g| Value::Real(g.max_distance),
        set: |g, v| g.max_distance = v as f32,
    },
    Field {
        axis: "start-offset",
        column: "start_offset",
        min: 0.0,
        max: 16.0,
        get: |g| Value::Real(g.start_offset),
        set: |g, v| g.start_offset = v as f32,
    },
    Field {
        axis: "ao-falloff",
        column: "ao_falloff",
        min: 0.0,
        max: 100.0,
        get: |g| Value::Real(g.ao_falloff),
        set: |g, v| g.ao_falloff = v as f32,
    },
    Field {
        axis: "voxel-shadows",
        column: "voxel_shadows",
        min: 0.0,
        max: 1.0,
        get: |g| Value::Switch(g.voxel_shadows),
        set: |g, v| g.voxel_shadows = v != 0.0,
    },
    Field {
        axis: "cone-shadows",
        column: "cone_shadows",
        min: 0.0,
        max: 1.0,
        get: |g| Value::Switch(g.cone_shadows),
        set: |g, v| g.cone_shadows = v != 0.0,
    },
    Field {
        axis: "paper-slips",
        column: "paper_slips",
        min: 0.0,
        max: 1.0,
        get: |g| Value::Switch(g.paper_slips),
        set: |g, v| g.paper_slips = v != 0.0,
    },
    Field {
        axis: "lod-offset",
        column: "lod_offset",
        min: 0.0,
        max: 4.0,
        get: |g| Value::Real(g.lod_offset),
        set: |g, v| g.lod_offset = v as f32,
    },
    Field {
        axis: "tail",
        column: "tail",
        min: 0.0,
        max: 1.0,
        get: |g| Value::Switch(g.tail),
        set: |g, v| g.tail = v != 0.0,
    },
    Field {
        axis: "area-lights",
        column: "area_lights",
        min: 0.0,
        max: 1.0,
        get: |g| Value::Switch(g.area_lights),
        set: |g, v| g.area_lights = v != 0.0,
    },
    Field {
        axis: "trace-scale",
        column: "trace_scale",
        min: 1.0,
        max: 4.0,
        get: |g| Value::Count(g.trace_scale),
        set: |g, v| g.trace_scale = v as u32,
    },
    Field {
        axis: "temporal",
        column: "temporal",
        min: 0.0,
        max: 16.0,
        get: |g| Value::Count(g.temporal),
        set: |g, v| g.temporal = v as u32,
    },
    Field {
        axis: "specular-min",
        column: "specular_min_voxels",
        min: 1.0,
        max: 8.0,
        get: |g| Value::Real(g.specular_min_voxels),
        set: |g, v| g.specular_min_voxels = v as f32,
    },
    Field {
        axis: "empty-space",
        column: "empty_space",
        min: 0.0,
        max: 1.0,
        get: |g| Value::Switch(g.empty_space),
        set: |g, v| g.empty_space = v != 0.0,
    },
    Field {
        axis: "backs",
        column: "backs",
        min: 0.0,
        max: 1.0,
        get: |g| Value::Switch(g.backs),
        set: |g, v| g.backs = v != 0.0,
    },
    Field {
        axis: "bounce-share",
        column: "bounce_share",
        min: 0.0,
        max: 1.0,
        get: |g| Value::Switch(g.bounce_share),
        set: |g, v| g.bounce_share = v != 0.0,
    },
];

/// Empties a list that drives an indirect dispatch (the bounce's filled voxels, the trace's
/// unmatched pixels, the lighting's pixels for the area lights' faces): its header, dispatch (0, 1, 1) and count 0.
pub(crate) fn record_list_clear(ctx: &Context, g: &mut Graph, list: &Buffer, name: &str) {
    g.pass(name)
        .buffer(list, Access::TransferWrite)
        .record(|cmd| unsafe {
            let args: Vec<u8> = [0u32, 1, 1, 0]
                .iter()
                .flat_map(|w| w.to_le_bytes())
                .collect();
            ctx.device.cmd_update_buffer(cmd, list.raw, 0, &args);
        });
}

/// What the RGBA16F radiance volumes are scaled by: 1, unless the brightest voxel could come
/// near the half float's largest value (65504), e.g. a 1e6 W/sr light. The bound: a white voxel
/// one voxel from a point or spot light, lit head-on by a directional one, or the strongest
/// emitter; kept under 1e4 to leave room for the second bounce and the mips' sums.
pub fn radiance_scale(scene: &crate::scene::Scene, voxel_size: f32, max_emission: f32) -> f32 {
    use crate::scene::LightKind;
    let brightest = scene
        .lights
        .iter()
        .map(|l| {
            let i = l.radiance.max_element();
            match l.kind {
                LightKind::Directional => i,
                _ => i / (voxel_size * voxel_size),
            }
        })
        .fold(max_emission, f32::max);
    if brightest.is_finite() && brightest > 1e4 {
        1e4 / brightest
    } else {
        1.0
    }
}

/// The voxel grid: a cube over the scene bounds, N voxels per side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelGrid {
    pub origin: Vec3,
    pub size: f32,
    pub resolution: u32,
}

impl VoxelGrid {
    /// A cube of the bounds' largest extent, centred on them, one voxel wider on each side so
    /// that surfaces on the bounds lie inside.
    pub fn fit(bounds: &Aabb, resolution: u32) -> VoxelGrid {
        let resolution = resolution.max(2);
        if bounds.is_empty() {
            return VoxelGrid {
                origin: Vec3::splat(-1.0),
                size: 2.0,
                resolution,
            };
        }
        let extent = bounds.extent().max_element().max(1e-4);
        let size = extent * resolution as f32 / (resolution as f32 - 2.0).max(1.0);
        VoxelGrid {
            origin: bounds.center() - Vec3::splat(size * 0.5),
            size,
            resolution,
        }
    }
    pub fn voxel_size(&self) -> f32 {
        self.size / self.resolution as f32
    }
    /// Texels per side of the directional volumes' base level: half the grid, rounded up.
    /// Vulkan rounds mip sizes down; the default's mip pass folds the texel a level of odd size
    /// would drop into the last texel of the next (aniso_mip_volume.comp), so every level ends
    /// where the grid does; `--paper` drops it. (Padded up to a power of two instead, the
    /// levels lined up with the grid exactly, but walls at the grid's far end fell in coarse
    /// texels mostly past it, and how much light a closed room kept depended on the grid's
    /// size.)
    pub fn aniso_resolution(&self) -> u32 {
        self.resolution.div_ceil(2)
    }
    /// Mip levels of the directional volumes (their base level down to 1 texel).
    pub fn mip_levels(&self) -> u32 {
        32 - self.aniso_resolution().leading_zeros()
    }
    /// Voxels per side of the empty-space cells (src/gi/empty_space.rs): a power of two, at
    /// least 2 (a cone's sample reaches a voxel and a half), with at most 64 cells a side (each
    /// line of cells is transformed in O(cells^2)).
    pub fn empty_space_cell(&self) -> u32 {
        self.resolution.div_ceil(64).next_power_of_two().max(2)
    }
    /// Empty-space cells per side.
    pub fn empty_space_resolution(&self) -> u32 {
        self.resolution.div_ceil(self.empty_space_cell())
    }
}

/// Diffuse cones over the hemisphere around +Z: direction and weight, weights summing to pi
/// (cosine-weighted solid angle). One cone along the normal covers the cap of the cone's half
/// aperture; the rest share the band below it, tilted to the band's cosine-weighted mean angle.
/// With 6 cones of 60 degrees this gives the paper's weights (pi/4 and 3pi/20). Many narrow
/// cones on one ring at a single tilt leave the directions between it and the normal cone, and
/// those near the surface, to no cone; so the cones go on two rings (a third of them on the
/// inner one) when that leaves less of the hemisphere outside every cone.
pub fn cone_set(count: u32, aperture_deg: f32, paper: bool) -> Vec<Vec4> {
    let count = count.clamp(1, 16);
    let pi = std::f32::consts::PI;
    if paper {
        // The original's directions: the ring offset (0.866) is added to the normal, so the cones
        // tilt ~40.9 degrees, not the intended 60.
        let mut cones = vec![Vec4::new(0.0, 0.0, 1.0, pi / 4.0)];
        for k in 0..5 {
            let phi = k as f32 * 2.0 * pi / 5.0;
            let d = Vec3::new(0.866 * phi.cos(), 0.866 * phi.sin(), 1.0).normalize();
            cones.push(d.extend(3.0 * pi / 20.0));
        }
        return cones;
    }
    if count == 1 {
        return vec![Vec4::new(0.0, 0.0, 1.0, pi)];
    }
    let beta = (aperture_deg.to_radians() * 0.5).clamp(0.01, 1.5);
    let half_pi = std::f32::consts::FRAC_PI_2;
    let rest = count - 1;
    let one = rings(beta, &[(rest, beta, half_pi)]);
    if rest < 3 {
        return one;
    }
    // Two polar bands whose shares of the cosine-weighted solid angle match their shares of the
    // cones, so that all ring cones weigh the same.
    let inner = (rest + 1) / 3;
    let sin2 = beta.sin().powi(2);
    let split = (sin2 + (1.0 - sin2) * inner as f32 / rest as f32)
        .sqrt()
        .asin();
    let two = rings(
        beta,
        &[(inner, beta, split), (rest - inner, split, half_pi)],
    );
    if uncovered(&two, beta) < uncovered(&one, beta) {
        two
    } else {
        one
    }
}

/// The normal cone (half angle `beta`, weighing its cap), then for each polar band
/// `(n, from, to)` a ring of `n` cones sharing the band's weight.
fn rings(beta: f32, bands: &[(u32, f32, f32)]) -> Vec<Vec4> {
    let pi = std::f32::consts::PI;
    let sin2 = |t: f32| t.sin().powi(2);
    // Cones tilted further than 15 degrees above the surface with their edge would mostly see
    // the surface they leave.
    let steepest = std::f32::consts::FRAC_PI_2 - beta - 15f32.to_radians();
    let mut cones = vec![Vec4::new(0.0, 0.0, 1.0, pi * sin2(beta))];
    for (ring, &(n, from, to)) in bands.iter().enumerate() {
        let tilt = cosine_weighted_mean_angle(from, to).min(steepest);
        let weight = pi * (sin2(to) - sin2(from)) / n as f32;
        // The outer ring's cones sit between the inner ring's.
        let offset = 0.5 * ring as f32;
        for k in 0..n {
            let phi = (k as f32 + offset) * 2.0 * pi / n as f32;
            let d = Vec3::new(tilt.sin() * phi.cos(), tilt.sin() * phi.sin(), tilt.cos());
            cones.push(d.extend(weight));
        }
    }
    cones
}

/// The share of the hemisphere's cosine-weighted solid angle that lies outside every cone of
/// half angle `beta` (0: each direction is seen by some cone).
fn uncovered(cones: &[Vec4], beta: f32) -> f32 {
    let (rows, cols) = (90, 180);
    let cos_beta = beta.cos();
    let (mut outside, mut total) = (0.0f64, 0.0f64);
    for i in 0..rows {
        let theta = std::f32::consts::FRAC_PI_2 * (i as f32 + 0.5) / rows as f32;
        let w = (theta.cos() * theta.sin()) as f64;
        for j in 0..cols {
            let phi = std::f32::consts::TAU * j as f32 / cols as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            total += w;
            if cones.iter().all(|c| c.truncate().dot(d) < cos_beta) {
                outside += w;
            }
        }
    }
    (outside / total) as f32
}

/// The mean polar angle over the band [from, to] of the hemisphere, weighted by cos x sin
/// (cosine-weighted solid angle), integrated numerically.
fn cosine_weighted_mean_angle(from: f32, to: f32) -> f32 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    let steps = 512;
    for i in 0..steps {
        let t = from as f64 + (to - from) as f64 * (i as f64 + 0.5) / steps as f64;
        let w = t.cos() * t.sin();
        num += t * w;
        den += w;
    }
    (num / den) as f32
}

/// Bits of frame.grid_info.w (glsl/common.glsl).
pub const FLAG_DYNAMIC: u32 = 1;
pub const FLAG_EMISSIVE: u32 = 2;
pub const FLAG_VOXEL_SHADOWS: u32 = 4;
pub const FLAG_CONE_SHADOWS: u32 = 8;
pub const FLAG_EMPTY_SPACE: u32 = 16;
pub const FLAG_PAPER_SLIPS: u32 = 32;
pub const FLAG_BACKS: u32 = 64;
pub const FLAG_BOUNCE_SHARE: u32 = 128;

/// The voxel passes a renderer runs: only those its mode and scene need.
pub struct Gi {
    pub settings: GiSettings,
    pub volumes: Volumes,
    pub voxelizer: Voxelizer,
    /// Inject and mips: absent when the mode only shows the voxels' materials.
    pub lighting: Option<(Inject, Mip)>,
    /// Where cones may skip (not for --paper; absent without lighting).
    pub empty_space: Option<EmptySpace>,
    pub bounce: Option<Bounce>,
    pub trace: Trace,
    pub cones: Vec<Vec4>,
    /// The bounces' cones (GiSettings::bounce_cone_count).
    pub bounce_cones: Vec<Vec4>,
    pub emissive: bool,
    pub dynamic: bool,
    /// Scale of the emission sums (fixed point per unit radiance).
    pub emission_scale: f32,
    /// The radiance volumes hold radiance x this (see [`radiance_scale`]).
    pub radiance_scale: f32,
    /// What the next frame must redo (everything, on the first).
    pub dirty: Dirty,
}

/// What `Gi::new` needs from the renderer.
pub struct GiInputs<'a> {
    /// The scene's set (set 0: frame uniforms, materials, lights, shadow views).
    pub scene: &'a SharedSet,
    /// The materials' sets (set 1 of voxelization).
    pub materials: &'a SharedSet,
    pub shadow_maps: ShadowMapsIn<'a>,
    pub frame: FrameImages<'a>,
    /// The scene's vertices as voxelization reads them, and each draw's push constants.
    pub vertices: VertexLayout<'a>,
    pub draw_push_size: u32,
    /// The emitters injected as lights: each one's instance (whose emission stays out of the
    /// voxels) and its emission's brightest channel.
    pub area_lights: &'a [(usize, f32)],
    /// The bounce's list's first capacity (None: `bounce::list_capacity`).
    pub list_capacity: Option<u64>,
}

/// What [`Gi::fit_voxel_list`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ListFit {
    /// The list held every filled voxel (or was not made this frame).
    Fits,
    /// It did not; it now holds `to` (from `from`) and the voxels are marked to run again.
    Grown { from: u64, to: u64 },
    /// It did not, and cannot grow further: `count` filled voxels, `capacity` with a bounce.
    Short { count: u64, capacity: u64 },
}

impl Gi {
    pub fn new(
        ctx: &Arc<Context>,
        scene: &crate::scene::Scene,
        settings: &GiSettings,
        light_voxels: bool,
        dynamic: bool,
        inputs: GiInputs,
    ) -> VkResult<Gi> {
        // Nodes that move may go where a ground's far part was; the original's grid covers the
        // whole scene.
        let bounds = if dynamic || settings.paper {
            scene.bounds
        } else {
            scene.voxel_bounds()
        };
        let grid = VoxelGrid::fit(&bounds, settings.voxels);
        if bounds != scene.bounds {
            log::info!(
                "a ground plane reaches past the rest of the scene: the voxel grid covers {:.1} m \
                 of its {:.1} m (voxels of {:.3} m)",
                bounds.extent().max_element(),
                scene.bounds.extent().max_element(),
                grid.voxel_size()
            );
        }
        // The emission the voxels hold: every emissive instance's but the lights'.
        let max_emission = scene
            .instances
            .iter()
            .enumerate()
            .filter(|(i, _)| !inputs.area_lights.iter().any(|e| e.0 == *i))
            .filter_map(|(_, inst)| scene.primitives.get(inst.primitive as usize))
            .filter_map(|p| scene.materials.get(p.material as usize))
            .map(|m| m.emissive.max_element())
            .fold(0.0f32, f32::max);
        let emissive = max_emission > 0.0;
        let volumes = Volumes::new(ctx, grid, settings, emissive, dynamic)?;
        let paper = settings.paper;
        let scene_set = inputs.scene;
        let voxelizer = Voxelizer::new(
            ctx,
            &[scene_set, inputs.materials],
            &volumes,
            inputs.vertices,
            inputs.draw_push_size,
            paper,
        )?;
        let lighting = if light_voxels {
            Some((
                Inject::new(ctx, scene_set, &volumes, inputs.shadow_maps, paper)?,
                Mip::new(ctx, &volumes, paper)?,
            ))
        } else {
            None
        };
        let empty_space = if light_voxels && settings.empty_space {
            EmptySpace::new(ctx, &volumes)?
        } else {
            None
        };
        let bounce = if light_voxels && settings.bounces >= 2 {
            let n = volumes.grid.resolution;
            let capacity = inputs
                .list_capacity
                .unwrap_or_else(|| bounce::list_capacity(n));
            let backs = volumes.holds_backs();
            let capacity = capacity.clamp(1, bounce::list_capacity_limit(ctx, n, paper, backs));
            Some(Bounce::new(ctx, scene_set, &volumes, settings, capacity)?)
        } else {
            None
        };
        let layout = TraceLayout {
            scale: settings.trace_scale.max(1),
            temporal: settings.temporal,
        };
        let trace = Trace::new(ctx, scene_set, &volumes, &inputs.frame, paper, layout)?;
        Ok(Gi {
            cones: cone_set(settings.cone_count, settings.cone_aperture_deg, paper),
            bounce_cones: cone_set(
                settings.bounce_cone_count,
                settings.bounce_cone_aperture_deg,
                false,
            ),
            settings: settings.clone(),
            volumes,
            voxelizer,
            lighting,
            empty_space,
            bounce,
            trace,
            emissive,
            dynamic,
            emission_scale: 4096.0 / max_emission.max(1e-6),
            radiance_scale: if paper {
                1.0
            } else {
                // The emitters' lights as bright as their emission at most: a face no larger
                // than the voxel, one voxel away.
                let lights = inputs
                    .area_lights
                    .iter()
                    .map(|e| e.1)
                    .fold(max_emission, f32::max);
                radiance_scale(scene, grid.voxel_size(), lights)
            },
            dirty: Dirty::ALL,
        })
    }

    pub fn flags(&self) -> u32 {
        let flag = |on: bool, f: u32| if on { f } else { 0 };
        flag(self.dynamic, FLAG_DYNAMIC)
            | flag(self.emissive, FLAG_EMISSIVE)
            | flag(self.settings.voxel_shadows, FLAG_VOXEL_SHADOWS)
            | flag(self.settings.cone_shadows, FLAG_CONE_SHADOWS)
            | flag(self.empty_space.is_some(), FLAG_EMPTY_SPACE)
            | flag(
                self.settings.paper && self.settings.paper_slips,
                FLAG_PAPER_SLIPS,
            )
            | flag(self.volumes.holds_backs(), FLAG_BACKS)
            | flag(
                self.bounce.as_ref().is_some_and(|b| b.shares()),
                FLAG_BOUNCE_SHARE,
            )
    }

    /// The voxel passes a frame records when `dirty` says what changed, in order: the volumes
    /// keep the last frame's light, bounces included, until a node or a light moves, so a
    /// still frame records none (it only traces).
    pub fn steps(&self, dirty: Dirty) -> Vec<Step> {
        let mut steps = Vec::new();
        if dirty.static_voxels {
            steps.extend([
                Step::Clear { dynamic: false },
                Step::Voxelize { dynamic: false },
            ]);
        }
        // The static pass may clear the dynamic voxels too (the paper's clears all).
        let dynamic_changed = self.dynamic && (dirty.static_voxels || dirty.dynamic_voxels);
        if dynamic_changed {
            steps.extend([
                Step::Clear { dynamic: true },
                Step::Voxelize { dynamic: true },
            ]);
        }
        let voxels_changed = dirty.static_voxels || dynamic_changed;
        if !(voxels_changed || dirty.lights) || self.lighting.is_none() {
            return steps;
        }
        steps.extend([
            Step::Inject { bounce: 1 },
            Step::MipBase { bounce: 1 },
            Step::MipLevels { bounce: 1 },
        ]);
        // Which voxels are filled changes only with them; the bounces' cones skip by it too.
        if voxels_changed && self.empty_space.is_some() {
            steps.push(Step::EmptySpace);
        }
        let Some(b) = &self.bounce else {
            return steps;
        };
        let last = self.settings.bounces;
        for bounce in 2..=last {
            // The bounce adds to the radiance volume in place, so from the third on the direct
            // light is injected again first; the directional volumes still hold the light of
            // the bounces before.
            if bounce > 2 {
                steps.push(Step::Inject { bounce });
            }
            // The list of filled voxels holds until the voxels change.
            if voxels_changed && bounce == 2 {
                steps.extend([Step::VoxelListClear, Step::VoxelList]);
            }
            if b.adds_separately() {
                steps.push(Step::SumsClear { bounce });
            }
            if b.shares() {
                steps.push(Step::ShareGather { bounce });
            }
            steps.push(Step::Gather { bounce });
            if b.adds_separately() {
                steps.push(Step::Add {
                    bounce,
                    last: bounce == last,
                });
            }
            steps.extend([Step::MipBase { bounce }, Step::MipLevels { bounce }]);
        }
        steps
    }

    /// Records one step of [`Gi::steps`].
    pub fn record_step(&self, ctx: &Context, g: &mut Graph, step: Step, input: &StepInputs) {
        let name = step.name();
        let v = &self.volumes;
        let lighting = || {
            self.lighting
                .as_ref()
                .expect("a lighting step without lighting")
        };
        let bounce = || self.bounce.as_ref().expect("a bounce step without bounces");
        match step {
            Step::Clear { dynamic } => self.voxelizer.record_clear(ctx, g, v, dynamic, &name),
            Step::Voxelize { dynamic } => {
                let draw = if dynamic {
                    input.draw_dynamic
                } else {
                    input.draw_static
                };
                self.voxelizer
                    .record_voxelize(ctx, g, v, input.geometry, dynamic, &name, draw)
            }
            Step::Inject { .. } => lighting().0.record(ctx, g, v, input.scene_set, &name),
            Step::MipBase { bounce } => lighting().1.record_base(ctx, g, v, &name, bounce == 1),
            Step::MipLevels { bounce } => lighting().1.record_levels(ctx, g, v, &name, bounce == 1),
            Step::EmptySpace => {
                let e = self
                    .empty_space
                    .as_ref()
                    .expect("an empty-space step without it");
                e.record(ctx, g, v, &name)
            }
            Step::VoxelListClear => bounce().record_list_clear(ctx, g, &name),
            Step::VoxelList => bounce().record_list(ctx, g, v, input.scene_set, &name),
            Step::SumsClear { .. } => bounce().record_sums_clear(ctx, g, &name),
            Step::ShareGather { .. } => bounce().record_share(ctx, g, v, input.scene_set, &name),
            Step::Gather { bounce: b } => bounce().record_gather(ctx, g, input.scene_set, b, &name),
            Step::Add { bounce: b, last } => {
                bounce().record_add(ctx, g, input.scene_set, b, last, &name)
            }
        }
    }

    /// The voxel passes have run for the current scene and lights.
    pub fn mark_clean(&mut self) {
        self.dirty = Dirty::NONE;
    }

    /// After a frame that listed the filled voxels (its fence waited): when the bounce's list
    /// could not hold them all, a list that holds a quarter more (within the device's limit),
    /// and the voxels marked to be listed and lit again. `forget` is told each buffer freed.
    pub fn fit_voxel_list(
        &mut self,
        ctx: &Arc<Context>,
        scene_set: &SharedSet,
        forget: &mut dyn FnMut(vk::Buffer),
    ) -> VkResult<ListFit> {
        let Some(b) = &self.bounce else {
            return Ok(ListFit::Fits);
        };
        let Some(count) = b.overflow() else {
            return Ok(ListFit::Fits);
        };
        let from = b.capacity();
        let n = self.volumes.grid.resolution;
        let (paper, backs) = (self.settings.paper, self.volumes.holds_backs());
        let limit = bounce::list_capacity_limit(ctx, n, paper, backs);
        let to = (count + count / 4).min(limit);
        if to <= from {
            return Ok(ListFit::Short {
                count,
                capacity: from,
            });
        }
        for raw in b.buffers() {
            forget(raw);
        }
        self.bounce = None;
        self.bounce = Some(Bounce::new(
            ctx,
            scene_set,
            &self.volumes,
            &self.settings,
            to,
        )?);
        self.dirty = Dirty::ALL;
        Ok(ListFit::Grown { from, to })
    }
}

/// What the voxels need redone before a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Dirty {
    /// Static geometry must be voxelized (first frame, or a static node moved).
    pub static_voxels: bool,
    /// Dynamic geometry must be voxelized again (first frame, or a dynamic node moved).
    pub dynamic_voxels: bool,
    /// The voxels must be lit again: a light changed (or the first frame).
    pub lights: bool,
}

impl Dirty {
    /// The first frame's: everything.
    pub const ALL: Dirty = Dirty {
        static_voxels: true,
        dynamic_voxels: true,
        lights: true,
    };
    /// A still frame's: nothing.
    pub const NONE: Dirty = Dirty {
        static_voxels: false,
        dynamic_voxels: false,
        lights: false,
    };
}

/// One pass of the voxel side of a frame ([`Gi::steps`]). Its name is its debug label, its
/// timing's name and what `voxgi info` lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Clears what the static (or the dynamic) voxelization rebuilds.
    Clear {
        dynamic: bool,
    },
    /// Step 1: voxelization of the static (or the dynamic) geometry.
    Voxelize {
        dynamic: bool,
    },
    /// Step 2: direct light into the voxels, for light bounce `bounce` (1: the first; again
    /// before each bounce from the third).
    Inject {
        bounce: u32,
    },
    /// Step 3: the directional volumes' base level, then their mip levels (a pass per level),
    /// after light bounce `bounce`.
    MipBase {
        bounce: u32,
    },
    MipLevels {
        bounce: u32,
    },
    /// Where the grid is empty, for cones to skip: which cells hold a filled voxel, then each
    /// cell's distance to the nearest that does.
    EmptySpace,
    /// The list of filled voxels the bounces run over: its count cleared, then filled.
    VoxelListClear,
    VoxelList,
    /// The second (and later) bounce: the reflectance sums cleared, each listed voxel's gather,
    /// and what it gathered added to the radiance (`last`: with the bounces not traced).
    SumsClear {
        bounce: u32,
    },
    /// With `GiSettings::bounce_share`: each block's gather, before the voxels'.
    ShareGather {
        bounce: u32,
    },
    Gather {
        bounce: u32,
    },
    Add {
        bounce: u32,
        last: bool,
    },
}

impl Step {
    /// The pass's name: "bounce" and " (bounce)" tell the second bounce's passes apart, "bounce
    /// 3" and " (bounce 3)" the third's.
    pub fn name(&self) -> String {
        let kind = |dynamic: bool| if dynamic { "dynamic" } else { "static" };
        let suffix = |bounce: u32| match bounce {
            1 => String::new(),
            2 => " (bounce)".into(),
            k => format!(" (bounce {k})"),
        };
        let bounce_name = |bounce: u32| match bounce {
            2 => "bounce".to_string(),
            k => format!("bounce {k}"),
        };
        match *self {
            Step::Clear { dynamic } => format!("clear {}", kind(dynamic)),
            Step::Voxelize { dynamic } => format!("voxelize {}", kind(dynamic)),
            Step::Inject { bounce } => format!("inject{}", suffix(bounce)),
            Step::MipBase { bounce } => format!("mip base{}", suffix(bounce)),
            Step::MipLevels { bounce } => format!("mip volume{}", suffix(bounce)),
            Step::EmptySpace => "empty space".into(),
            Step::VoxelListClear => "voxel list clear".into(),
            Step::VoxelList => "voxel list".into(),
            Step::SumsClear { bounce } => format!("{} sums clear", bounce_name(bounce)),
            Step::ShareGather { bounce } => format!("{} blocks", bounce_name(bounce)),
            Step::Gather { bounce } => bounce_name(bounce),
            Step::Add { bounce, .. } => format!("{} add", bounce_name(bounce)),
        }
    }
}

/// What the voxel steps need from the renderer.
pub struct StepInputs<'a> {
    /// The scene's vertex and index buffers, which voxelization draws from.
    pub geometry: (&'a Buffer, &'a Buffer),
    pub scene_set: vk::DescriptorSet,
    pub draw_static: VoxelDraws<'a>,
    pub draw_dynamic: VoxelDraws<'a>,
}

/// The static (or the dynamic) instances, as voxelization draws them.
#[derive(Clone, Copy)]
pub struct VoxelDraws<'a> {
    pub count: usize,
    /// Draws those of the range (of `0..count`) with the voxelization pipeline and the given
    /// push-constant flags.
    pub draw: &'a DrawRange<'a>,
}

/// Draws a range of instances with a pipeline and push-constant flags.
pub type DrawRange<'a> = dyn Fn(vk::CommandBuffer, &Pipeline, u32, Range<usize>) + 'a;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone_weights_sum_to_pi_and_match_the_paper() {
        for aperture in [30.0, 36.0, 45.0, 60.0, 90.0] {
            for n in 1..=16 {
                let s: f32 = cone_set(n, aperture, false).iter().map(|c| c.w).sum();
                assert!(
                    (s - std::f32::consts::PI).abs() < 1e-4,
                    "{n} cones of {aperture} degrees sum to {s}"
                );
            }
        }
        let six = cone_set(6, 60.0, false);
        assert!((six[0].w - std::f32::consts::PI / 4.0).abs() < 1e-5);
        assert!((six[1].w - 3.0 * std::f32::consts::PI / 20.0).abs() < 1e-5);
        let paper: f32 = cone_set(6, 60.0, true).iter().map(|c| c.w).sum();
        assert!((paper - std::f32::consts::PI).abs() < 1e-5);
    }

    #[test]
    fn many_narrow_cones_go_on_two_rings_that_leave_less_unseen() {
        let tilts = |c: &[Vec4]| {
            let mut t: Vec<i32> = c.iter().map(|c| (c.z * 1e4) as i32).collect();
            t.sort();
            t.dedup();
            t.len()
        };
        // The paper's count and aperture keep one ring.
        assert_eq!(tilts(&cone_set(6, 60.0, false)), 2);
        let beta = 18f32.to_radians();
        let sixteen = cone_set(16, 36.0, false);
        assert_eq!(
            tilts(&sixteen),
            3,
            "16 cones of 36 degrees: normal and two rings"
        );
        // One ring of 15 at the band's mean tilt, as before two rings.
        let one = rings(beta, &[(15, beta, std::f32::consts::FRAC_PI_2)]);
        let (two_out, one_out) = (uncovered(&sixteen, beta), uncovered(&one, beta));
        assert!(
            two_out < 0.15 && one_out > 0.3,
            "outside every cone: two rings {two_out}, one ring {one_out}"
        );
    }

    #[test]
    fn empty_space_cells_cover_the_grid_in_at_most_64_a_side() {
        for n in [4, 8, 20, 48, 64, 100, 128, 256, 512, 1024] {
            let g = VoxelGrid {
                origin: Vec3::ZERO,
                size: 1.0,
                resolution: n,
            };
            let (c, m) = (g.empty_space_cell(), g.empty_space_resolution());
            assert!(
                c.is_power_of_two() && c >= 2 && m <= 64 && m * c >= n && (m - 1) * c < n,
                "{n}^3: cells of {c}, {m} a side"
            );
        }
        let g = VoxelGrid {
            origin: Vec3::ZERO,
            size: 1.0,
            resolution: 64,
        };
        assert_eq!((g.empty_space_cell(), g.empty_space_resolution()), (2, 32));
    }

    #[test]
    fn every_setting_has_its_field_and_each_field_sets_its_setting() {
        // Naming every field: a new one fails to compile here until it is counted.
        let GiSettings {
            voxels: _,
            bounces: _,
            paper: _,
            cone_count: _,
            cone_aperture_deg: _,
            bounce_cone_count: _,
            bounce_cone_aperture_deg: _,
            step_factor: _,
            max_distance: _,
            start_offset: _,
            ao_falloff: _,
            voxel_shadows: _,
            cone_shadows: _,
            paper_slips: _,
            lod_offset: _,
            tail: _,
            area_lights: _,
            trace_scale: _,
            temporal: _,
            specular_min_voxels: _,
            empty_space: _,
            backs: _,
            bounce_share: _,
        } = GiSettings::default();
        assert_eq!(FIELDS.len(), 23, "a setting without its line in FIELDS");
        for f in FIELDS {
            let d = GiSettings::default();
            let mut g = d.clone();
            // A value in range and unlike the default's.
            let v = if (f.get)(&d).as_f64() == f.max {
                f.min
            } else {
                f.max
            };
            (f.set)(&mut g, v);
            assert_eq!((f.get)(&g).as_f64() as f32, v as f32, "{}", f.axis);
            assert_ne!(g, d, "{} sets nothing", f.axis);
        }
    }

    #[test]
    fn grid_holds_the_bounds_with_a_margin() {
        let b = Aabb {
            min: Vec3::new(-1.0, 0.0, -2.0),
            max: Vec3::new(1.0, 3.0, 2.0),
        };
        let g = VoxelGrid::fit(&b, 64);
        assert!(g.origin.cmple(b.min - g.voxel_size() * 0.99).all());
        assert!((g.origin + g.size)
            .cmpge(b.max + g.voxel_size() * 0.99)
            .all());
        assert_eq!(VoxelGrid::fit(&b, 8).mip_levels(), 3); // 4, 2, 1
        assert_eq!(VoxelGrid::fit(&b, 37).mip_levels(), 5); // 19, 9, 4, 2, 1
        assert_eq!(VoxelGrid::fit(&b, 37).aniso_resolution(), 19);
        assert_eq!(VoxelGrid::fit(&b, 64).aniso_resolution(), 32);
    }

    #[test]
    fn every_mip_level_ends_where_the_grid_does() {
        // Level L has max(1, m >> L) texels (Vulkan); texel i holds texels 2i and 2i + 1 of
        // the level below, the last one also 2i + 2 where that level has an odd size
        // (aniso_mip_volume.comp). Follow each texel's base texels down the chain: they tile
        // the base level, and the last texel of every level reaches its end.
        let b = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        for n in 2..=600 {
            let g = VoxelGrid::fit(&b, n);
            let m = g.aniso_resolution();
            assert!(2 * m >= n, "{n}^3: {m} texels do not cover the grid");
            // Each texel's range of base texels, level by level.
            let mut ranges: Vec<(u32, u32)> = (0..m).map(|i| (i, i + 1)).collect();
            for level in 1..g.mip_levels() {
                let size = (m >> level).max(1);
                let below = ranges.clone();
                ranges = (0..size)
                    .map(|i| {
                        let lo = 2 * i as usize;
                        let hi = if i + 1 == size { below.len() } else { lo + 2 };
                        (below[lo].0, below[hi - 1].1)
                    })
                    .collect();
                for w in ranges.windows(2) {
                    assert_eq!(w[0].1, w[1].0, "{n}^3, level {level}: a gap or overlap");
                }
                assert_eq!(ranges[0].0, 0);
                assert_eq!(
                    ranges.last().unwrap().1,
                    m,
                    "{n}^3, level {level}: the last texel stops short of the grid's end"
                );
                // No texel holds more than 3 of the level below along an axis.
                assert!(below.len() <= 2 * size as usize + 1, "{n}^3, level {level}");
            }
            assert_eq!(ranges.len(), 1, "{n}^3 ends at one texel");
        }
    }
}
