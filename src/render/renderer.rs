//! The renderer: a composition of the scene on the GPU, the sets the passes share, the frame's
//! targets, the shadow maps, the G-buffer and lighting passes, the instances and their motion,
//! and the voxel passes (crate::gi); each frame records the steps its state calls for.

use super::accumulate::{self, Accumulate};
use super::area_lights::{self, AreaLight};
use super::frame::FrameTargets;
use super::gbuffer::GBufferPass;
use super::gpu::FrameUniforms;
use super::gpu_scene::{light_table, GpuScene, ShadowResolution};
use super::instances::{self, Instances, SceneDraw, DRAW_PUSH_SIZE, NORMAL, POSITION, UV};
use super::lighting::{LightingInputs, LightingPass};
use super::scene_set::SceneBindings;
use super::shadow_maps::{ShadowLayout, ShadowMaps};
use crate::gi::{
    Dirty, FrameImages, Gi, GiInputs, GiSettings, ListFit, ShadowMapsIn, StepInputs, TraceFrame,
    TraceMode, VoxelDraws,
};
use crate::scene::{Aabb, Camera, Light, Scene};
use crate::vk::{
    vk, CommandPool, Context, Graph, Image, PassTimer, Pipeline, ResourceStates, Sampler, VkError,
    VkResult,
};
use glam::{Mat4, Vec4};
use std::ops::Range;
use std::sync::Arc;

/// What the image shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Direct and indirect light (cone traced), plus emission.
    Full,
    /// Punctual lights with shadows, plus emission.
    Direct,
    /// Only the cone-traced indirect light.
    Indirect,
    /// Ambient occlusion from the voxels (grey).
    Ao,
    /// The first voxel along each camera ray: its albedo, normal, emission or radiance
    /// (radiance with `mip`: the directional volumes at that level).
    VoxelsAlbedo,
    VoxelsNormal,
    VoxelsEmission,
    VoxelsRadiance,
}

impl Mode {
    /// Every mode, in the order of [`Mode::NAMES`].
    pub const ALL: [Mode; 8] = [
        Mode::Full,
        Mode::Direct,
        Mode::Indirect,
        Mode::Ao,
        Mode::VoxelsAlbedo,
        Mode::VoxelsNormal,
        Mode::VoxelsEmission,
        Mode::VoxelsRadiance,
    ];

    pub const NAMES: &'static str =
        "full, direct, indirect, ao, voxels-albedo, voxels-normal, voxels-emission, voxels-radiance";

    /// Whether the voxel passes run at all.
    pub fn uses_voxels(self) -> bool {
        self != Mode::Direct
    }
    /// Whether the voxels are lit (inject and mips).
    pub fn lights_voxels(self) -> bool {
        matches!(
            self,
            Mode::Full | Mode::Indirect | Mode::Ao | Mode::VoxelsRadiance
        )
    }
    /// Whether the image comes from the G-buffer (else from walking the voxels).
    pub fn shades_pixels(self) -> bool {
        matches!(self, Mode::Full | Mode::Direct | Mode::Indirect | Mode::Ao)
    }
}

impl std::str::FromStr for Mode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s {
            "full" => Mode::Full,
            "direct" => Mode::Direct,
            "indirect" => Mode::Indirect,
            "ao" => Mode::Ao,
            "voxels-albedo" => Mode::VoxelsAlbedo,
            "voxels-normal" => Mode::VoxelsNormal,
            "voxels-emission" => Mode::VoxelsEmission,
            "voxels-radiance" => Mode::VoxelsRadiance,
            other => {
                return Err(format!(
                    "unknown render mode {other:?} (the modes are: {})",
                    Mode::NAMES
                ))
            }
        })
    }
}

/// One step of a frame. [`Renderer::steps`] lists a frame's in the order recorded; recording
/// and [`Renderer::passes`] (what `voxgi info` shows) walk the same list, and a step's name is
/// its pass's debug label and its name in `--timings`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// The shadow views that changed (every one on the first frame).
    Shadows,
    /// A pass of the voxel side: voxelization, light injection, mipmaps, bounces.
    Voxels(crate::gi::Step),
    GBuffer,
    /// Direct light per pixel from the G-buffer and the shadow maps.
    Lighting,
    /// With area lights and the default's voxels: the light of an emitter's faces at the
    /// pixels whose shadow views may hide them behind what it rests on (lighting.rs).
    AreaFaces,
    /// The diffuse cones per block of pixels or over frames (with a trace scale above 1 or a
    /// temporal trace), for the trace to upsample.
    Gather,
    /// Cones per pixel, added to the direct light (the modes that shade pixels).
    Trace,
    /// After a gather: the diffuse cones of the pixels no block holds, which the trace listed.
    TraceUnmatched,
    /// The first voxel along each camera ray (the voxel modes).
    VoxelView,
    /// The radiance blended into the mean of the frames since the view last changed
    /// (antialiasing: accumulate.rs).
    Accumulate,
    /// The radiance image copied to host memory.
    Readback,
}

impl Step {
    pub fn name(&self) -> String {
        match self {
            Step::Shadows => "shadows".into(),
            Step::Voxels(s) => s.name(),
            Step::GBuffer => "gbuffer".into(),
            Step::Lighting => "lighting".into(),
            Step::AreaFaces => "area faces".into(),
            Step::Gather => "gather".into(),
            Step::Trace => "trace".into(),
            Step::TraceUnmatched => "trace unmatched".into(),
            Step::VoxelView => "voxel view".into(),
            Step::Accumulate => "accumulate".into(),
            Step::Readback => "readback".into(),
        }
    }
}

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub mode: Mode,
    /// Texels per side of each punctual light's shadow-map views.
    pub shadow_resolution: u32,
    /// Texels per side of each area light's shadow-map views (soft shadows: coarser).
    pub area_shadow_resolution: u32,
    /// PCF kernel radius in texels (a (2r+1)^2 grid of bilinear comparisons).
    pub pcf_radius: u32,
    /// Normal offset of shadow lookups, in texels.
    pub normal_offset: f32,
    pub timings: bool,
    /// The voxel passes' settings.
    pub gi: GiSettings,
    /// With `Mode::VoxelsRadiance`: show the directional volumes at this mip level.
    pub mip: Option<u32>,
    /// Nodes that move between frames: voxelized every frame, apart from the static voxels.
    pub dynamic_nodes: Vec<usize>,
    /// Antialiasing: while the view holds still, the frames are drawn at sub-pixel offsets and
    /// the image is the mean of the first this many (later frames show it). 0 or 1: off,
    /// every pixel one sample at its centre.
    pub accumulate: u32,
    /// The first capacity of the bounce's list of filled voxels (None: every voxel of a grid up
    /// to 64^3, 64 N^2 beyond). A frame that lists more grows it to fit and renders again.
    pub voxel_list_capacity: Option<u64>,
}

impl RenderSettings {
    pub fn shadow_resolutions(&self) -> ShadowResolution {
        ShadowResolution {
            punctual: self.shadow_resolution,
            area: self.area_shadow_resolution,
        }
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 512,
            height: 512,
            mode: Mode::Full,
            shadow_resolution: 2048,
            area_shadow_resolution: 512,
            pcf_radius: 1,
            normal_offset: 1.5,
            timings: false,
            gi: GiSettings::default(),
            mip: None,
            dynamic_nodes: Vec::new(),
            accumulate: 8,
            voxel_list_capacity: None,
        }
    }
}

/// Renders a scene; owns every GPU object it uses. Its fields are declared in the reverse order
/// of their making, so they free themselves (after the device is idle) in that order.
pub struct Renderer {
    pub settings: RenderSettings,
    pub camera: Camera,
    /// Wall time of each frame from submission to its fence, in milliseconds.
    pub frame_ms: Vec<f64>,
    /// The passes the last frame recorded, in order, by their debug labels.
    pub recorded: Vec<String>,
    /// Test hook: record this pass without its barriers.
    pub omit_barriers_of: Option<String>,
    pub timer: Option<PassTimer>,
    commands: CommandPool,
    /// The voxel passes (absent in direct mode).
    pub gi: Option<Gi>,
    lighting: LightingPass,
    gbuffer: GBufferPass,
    shadows: ShadowMaps,
    nearest: Sampler,
    targets: FrameTargets,
    sets: SceneBindings,
    gpu: GpuScene,
    states: ResourceStates,
    instances: Instances,
    /// The scene's lights (set_lights replaces them), then the environment's sun.
    lights: Vec<Light>,
    /// The environment's sun at strength 1 (src/render/environment.rs), the last light.
    env_sun: Option<Light>,
    /// Emissive surfaces lit as area lights, after the scene's lights (area_lights.rs).
    area_lights: Vec<AreaLight>,
    /// Per instance: the area light it is, if any.
    area_light_of: Vec<Option<usize>>,
    /// The scene's bounds (light views are fitted to them).
    bounds: Aabb,
    /// The environment's frame uniform (src/render/environment.rs), and what its stored
    /// texels are multiplied by besides the strength.
    environment: Vec4,
    environment_texel_scale: f32,
    specular_needed: bool,
    /// Frames since the temporal trace's history began, and the camera of the last one.
    history_frames: u64,
    prev_view_proj: Mat4,
    /// The next frame drops the temporal trace's history.
    history_reset: bool,
    /// This frame's camera is the last one's; and the frames left until, after the camera
    /// stopped, every block of the temporal trace has traced its cones afresh.
    still: bool,
    refresh_left: u32,
    /// Antialiasing: the mean's pass (None when off), the frames in the mean so far, and the
    /// unjittered camera of the last frame (another one starts the mean again).
    accumulate: Option<Accumulate>,
    mean_frames: u32,
    mean_camera: Mat4,
    /// The bounce's list grew after the last frame (which missed some voxels' bounce), and
    /// whether the list's limit has been reported.
    voxel_list_grown: bool,
    voxel_list_short_told: bool,
    ctx: Arc<Context>,
}

/// The lights the renderer draws and the environment its cones see.
struct SceneLights {
    /// The scene's lights, then the environment's sun.
    lights: Vec<Light>,
    environment: Option<crate::scene::Environment>,
    /// The environment's sun at strength 1.
    env_sun: Option<Light>,
}

/// An environment image's sun is lit as a directional light (shadow maps, injection); the
/// cones see the rest of the sky.
fn scene_lights(scene: &Scene) -> SceneLights {
    let split = scene
        .environment
        .as_ref()
        .and_then(super::environment::split_sun);
    let mut lights = scene.lights.clone();
    let Some(split) = split else {
        return SceneLights {
            lights,
            environment: scene.environment.clone(),
            env_sun: None,
        };
    };
    let mut sun = split.sun.clone();
    sun.radiance *= split.rest.strength;
    log::info!(
        "the environment's sun: {} W/m^2 from {:?}, lit as a directional light",
        sun.radiance,
        (-sun.direction).to_array()
    );
    lights.push(sun);
    SceneLights {
        lights,
        environment: Some(split.rest),
        env_sun: Some(split.sun),
    }
}

impl Renderer {
    pub fn new(ctx: &Arc<Context>, scene: &Scene, settings: RenderSettings) -> VkResult<Renderer> {
        let mut states = ResourceStates::default();
        let SceneLights {
            lights,
            environment,
            env_sun,
        } = scene_lights(scene);
        let environment = environment.as_ref();
        let area_lights = area_lights_of(scene, &settings);
        let mut area_light_of = vec![None; scene.instances.len()];
        for (k, e) in area_lights.iter().enumerate() {
            area_light_of[e.instance] = Some(k);
        }
        let gpu = GpuScene::upload(
            ctx,
            scene,
            &lights,
            environment,
            &mut states,
            &area_lights,
            settings.shadow_resolutions(),
            settings.pcf_radius,
        )?;
        let instances = Instances::new(scene, &settings.dynamic_nodes);
        let sets = SceneBindings::new(ctx, scene, &gpu)?;
        let targets = FrameTargets::new(
            ctx,
            settings.width,
            settings.height,
            settings.accumulate > 1,
        )?;
        let accumulate = Accumulate::new(ctx, &targets)?;
        let nearest = nearest_sampler(ctx)?;
        let shadows = ShadowMaps::new(
            ctx,
            &sets,
            ShadowLayout {
                views: gpu.punctual_view_count,
                resolution: settings.shadow_resolution,
                area_views: gpu.shadow_view_count - gpu.punctual_view_count,
                area_resolution: settings.area_shadow_resolution,
            },
        )?;
        let gbuffer = GBufferPass::new(ctx, &sets)?;
        let lit: Vec<(usize, f32)> = area_lights
            .iter()
            .map(|e| (e.instance, e.emission.max_element()))
            .collect();
        let gi = if settings.mode.uses_voxels() {
            let inputs = GiInputs {
                scene: &sets.scene,
                materials: &sets.materials,
                shadow_maps: ShadowMapsIn {
                    map: &shadows.map,
                    area_map: &shadows.area_map,
                    sampler: &shadows.sampler,
                },
                frame: FrameImages {
                    size: (settings.width, settings.height),
                    gbuffer: &targets.gbuffer,
                    sampler: nearest.raw,
                    out: &targets.hdr,
                },
                vertices: instances::vertices(&[POSITION, NORMAL, UV]),
                draw_push_size: DRAW_PUSH_SIZE,
                area_lights: &lit,
                list_capacity: settings.voxel_list_capacity,
            };
            let light_voxels = settings.mode.lights_voxels();
            let dynamic = instances.any_dynamic();
            Some(Gi::new(
                ctx,
                scene,
                &settings.gi,
                light_voxels,
                dynamic,
                inputs,
            )?)
        } else {
            None
        };
        let lighting = LightingPass::new(
            ctx,
            &sets,
            &LightingInputs {
                targets: &targets,
                nearest: &nearest,
                shadow: &shadows,
                voxels: faces_voxels(gi.as_ref(), area_lights.len()),
            },
        )?;
        let commands = CommandPool::new(ctx)?;
        let timer = if settings.timings {
            PassTimer::new(ctx, 64)?
        } else {
            None
        };
        log::debug!(
            "renderer: {}x{}, {}, {} area lights, GPU memory in use {:.1} MiB",
            settings.width,
            settings.height,
            gi.as_ref().map_or("no GI".to_string(), |_| format!(
                "{}^3 voxels{}",
                settings.gi.voxels,
                if settings.gi.paper { " (--paper)" } else { "" }
            )),
            area_lights.len(),
            ctx.allocated_bytes() as f64 / 1048576.0
        );
        Ok(Renderer {
            camera: scene.camera.clone(),
            frame_ms: Vec::new(),
            recorded: Vec::new(),
            omit_barriers_of: None,
            timer,
            commands,
            gi,
            lighting,
            gbuffer,
            shadows,
            nearest,
            targets,
            sets,
            gpu,
            states,
            instances,
            lights,
            env_sun,
            area_lights,
            area_light_of,
            bounds: scene.bounds,
            environment: super::environment::uniform(environment),
            environment_texel_scale: super::environment::texel_scale(environment),
            specular_needed: scene
                .materials
                .iter()
                .any(|m| m.metallic > 0.0 || m.specular_factor > 0.0),
            history_frames: 0,
            prev_view_proj: Mat4::IDENTITY,
            history_reset: true,
            still: false,
            refresh_left: 0,
            accumulate,
            mean_frames: 0,
            mean_camera: Mat4::IDENTITY,
            voxel_list_grown: false,
            voxel_list_short_told: false,
            settings,
            ctx: ctx.clone(),
        })
    }

    /// The environment's frame uniform: without cones (no voxel passes: --mode direct) the
    /// lighting pass lights by it.
    fn environment_uniform(&self) -> Vec4 {
        let mut env = self.environment;
        if env.w > 0.0 && self.gi.is_none() {
            env.w = super::environment::LIGHTS_DIRECTLY;
        }
        env
    }

    /// The camera's view and projection (without the antialiasing's sub-pixel shift).
    fn view_proj(&self) -> (Mat4, Mat4) {
        let (w, h) = (self.settings.width, self.settings.height);
        let proj = Mat4::perspective_rh(
            self.camera.yfov,
            w as f32 / h as f32,
            self.camera.znear,
            self.camera.zfar,
        );
        (self.camera.view(), proj)
    }

    /// The camera's sub-pixel shift this frame, in clip space (antialiasing: the mean's
    /// frames sample the pixels' footprints).
    fn jitter(&self) -> Mat4 {
        if self.accumulate.is_none() {
            return Mat4::IDENTITY;
        }
        let (w, h) = (self.settings.width as f32, self.settings.height as f32);
        let o = accumulate::jitter(self.mean_frames);
        Mat4::from_translation(glam::Vec3::new(2.0 * o.x / w, 2.0 * o.y / h, 0.0))
    }

    /// The frame's uniforms: the camera, the lights' count, the shadow and voxel settings.
    fn uniforms(&self) -> FrameUniforms {
        let (w, h) = (self.settings.width, self.settings.height);
        let (view, proj) = self.view_proj();
        let mut u = FrameUniforms {
            view_proj: self.jitter() * proj * view,
            view,
            proj,
            eye: self.camera.eye().extend(1.0),
            counts: [
                (self.lights.len() + self.area_lights.len()) as u32,
                w,
                h,
                self.gpu.shadow_view_count,
            ],
            shadow: Vec4::new(
                self.settings.shadow_resolution as f32,
                self.settings.normal_offset,
                self.settings.pcf_radius as f32,
                0.0,
            ),
            area_shadow: Vec4::new(
                self.settings.area_shadow_resolution as f32,
                self.gpu.punctual_view_count as f32,
                super::shadows::soft_shadow_texels(self.settings.area_shadow_resolution) as f32,
                0.0,
            ),
            env: self.environment_uniform(),
            ..Default::default()
        };
        if let Some(gi) = &self.gi {
            let grid = gi.volumes.grid;
            let s = &gi.settings;
            u.grid = grid.origin.extend(grid.size);
            u.grid_info = [
                grid.resolution,
                s.bounces,
                gi.cones.len() as u32,
                gi.flags(),
            ];
            u.cone = Vec4::new(
                (s.cone_aperture_deg.to_radians() * 0.5).tan(),
                s.step_factor,
                s.max_distance,
                gi.emission_scale,
            );
            u.trace = Vec4::new(
                s.start_offset,
                if s.paper {
                    crate::gi::PAPER_AO_FALLOFF * 0.5 / grid.size
                } else {
                    s.ao_falloff / grid.voxel_size()
                },
                if self.specular_needed { 1.0 } else { 0.0 },
                self.settings.mip.unwrap_or(0) as f32,
            );
            u.tuning = Vec4::new(
                s.lod_offset,
                gi.radiance_scale,
                s.specular_min_voxels,
                grid.empty_space_cell() as f32,
            );
            for (dst, c) in u.cones.iter_mut().zip(&gi.cones) {
                *dst = *c;
            }
            u.bounce_cone = Vec4::new(
                (s.bounce_cone_aperture_deg.to_radians() * 0.5).tan(),
                gi.bounce_cones.len() as f32,
                0.0,
                0.0,
            );
            for (dst, c) in u.bounce_cones.iter_mut().zip(&gi.bounce_cones) {
                *dst = *c;
            }
        }
        u
    }

    /// Renders one frame and waits for it. With `readback`, the radiance image is copied to
    /// host memory for `radiance()`.
    pub fn render(&mut self, readback: bool) -> VkResult<()> {
        self.render_with(readback, &[], &[], &mut |_| {})?;
        // The frame listed more filled voxels than the bounce's list held: again with the
        // grown list (a window's next frame does the same).
        if std::mem::take(&mut self.voxel_list_grown) {
            self.render_with(readback, &[], &[], &mut |_| {})?;
        }
        Ok(())
    }

    /// The bounce's list of filled voxels: how many it holds.
    pub fn voxel_list_capacity(&self) -> Option<u64> {
        self.gi.as_ref()?.bounce.as_ref().map(|b| b.capacity())
    }

    /// After a frame that listed the filled voxels: grows the bounce's list when they did not
    /// fit (the voxels run again next frame), or says once that it cannot.
    fn fit_voxel_list(&mut self) -> VkResult<()> {
        let Some(gi) = self.gi.as_mut() else {
            return Ok(());
        };
        let states = &mut self.states;
        match gi.fit_voxel_list(&self.ctx, &self.sets.scene, &mut |b| states.forget(b))? {
            ListFit::Fits => {}
            ListFit::Grown { from, to } => {
                log::info!(
                    "the bounce's list of filled voxels held {from}; it now holds {to}, and the \
                     voxels are lit again"
                );
                self.voxel_list_grown = true;
                self.history_reset = true;
            }
            ListFit::Short { count, capacity } => {
                if !std::mem::replace(&mut self.voxel_list_short_told, true) {
                    log::warn!(
                        "the grid has {count} filled voxels and the bounce's list can hold at \
                         most {capacity} on this device: {} voxels get no bounce (a coarser \
                         grid, --voxels, fits)",
                        count - capacity
                    );
                }
            }
        }
        Ok(())
    }

    /// Renders one frame, letting `after` record further passes that read the radiance image
    /// ([`Renderer::radiance_image`]: a window's display pass) in the same command buffer,
    /// whose submission waits for `waits` and signals `signals`; then waits for it.
    pub fn render_with(
        &mut self,
        readback: bool,
        waits: &[vk::SemaphoreSubmitInfo],
        signals: &[vk::SemaphoreSubmitInfo],
        after: &mut dyn FnMut(&mut Graph),
    ) -> VkResult<()> {
        // The light in the voxels changes this frame: the temporal history is stale.
        if self.gi.as_ref().is_some_and(|gi| gi.dirty != Dirty::NONE) {
            self.history_reset = true;
        }
        // Anything that changes the image starts the antialiasing mean again: the camera, the
        // light (shadows or voxels), a cut, a resize (set_node_transform: a node).
        let (view, proj) = self.view_proj();
        let camera = proj * view;
        let moved = camera != self.mean_camera;
        self.still = !self.history_reset && !moved;
        if self.history_reset {
            self.refresh_left = 0;
        } else if moved {
            self.refresh_left = self.temporal_subsets();
        }
        // While the temporal trace refreshes its blocks after the camera stopped, the diffuse
        // light still changes: the mean starts when it is complete (its first frame is then
        // what a fresh start's first frame is).
        let refreshing = self.still && self.refresh_left > 0;
        if self.history_reset || self.shadows.any_dirty() || moved || refreshing {
            self.mean_frames = 0;
        }
        let uniforms = self.uniforms();
        self.sets.write_uniforms(&uniforms);
        // A history that starts over traces the subsets from the first again: the same frames
        // give the same images however many came before.
        if self.history_reset {
            self.history_frames = 0;
        }
        let ctx = self.ctx.clone();
        let cmd = self.commands.begin()?;
        let mut states = std::mem::take(&mut self.states);
        let mut timer = self.timer.take();
        let mut listed = false;
        {
            let mut g = Graph::new(&ctx, cmd, &mut states, timer.as_mut());
            g.omit_barriers_of = self.omit_barriers_of.clone();
            for step in self.steps(readback) {
                listed |= step == Step::Voxels(crate::gi::Step::VoxelList);
                self.record_step(&mut g, step);
            }
            after(&mut g);
            self.recorded = std::mem::take(&mut g.labels);
        }
        self.states = states;
        self.commands.end()?;
        let start = std::time::Instant::now();
        let submitted = ctx.submit_and_wait_with(cmd, waits, signals);
        let ms = start.elapsed().as_secs_f64() * 1e3;
        self.frame_ms.push(ms);
        crate::vk::timing::keep_recent(&mut self.frame_ms);
        log::trace!("frame of {ms:.1} ms: {}", self.recorded.join(", "));
        if let Some(t) = timer.as_mut() {
            t.collect()?;
        }
        self.timer = timer;
        submitted?;
        self.shadows.dirty.fill(false);
        self.history_frames += 1;
        self.prev_view_proj = uniforms.view_proj;
        self.history_reset = false;
        if refreshing {
            self.refresh_left -= 1;
        }
        self.mean_frames = self.mean_frames.saturating_add(1);
        self.mean_camera = camera;
        // The voxels now hold the geometry and its light until a node or a light moves.
        if let Some(gi) = self.gi.as_mut() {
            gi.mark_clean();
        }
        if listed {
            self.fit_voxel_list()?;
        }
        Ok(())
    }

    /// The steps of a frame drawn when `shadows` (a shadow view must be drawn again) and `voxels`
    /// say what changed, in the order recorded.
    fn steps_when(&self, shadows: bool, voxels: Dirty, readback: bool) -> Vec<Step> {
        let mut steps = Vec::new();
        // A shadow view changes only when its light moves or a node moves through it.
        if shadows {
            steps.push(Step::Shadows);
        }
        if let Some(gi) = &self.gi {
            steps.extend(gi.steps(voxels).into_iter().map(Step::Voxels));
        }
        let mode = self.settings.mode;
        if mode.shades_pixels() {
            steps.push(Step::GBuffer);
        }
        if matches!(mode, Mode::Full | Mode::Direct) {
            steps.push(Step::Lighting);
            if self.lighting.lists_faces() {
                steps.push(Step::AreaFaces);
            }
        }
        if let Some(gi) = &self.gi {
            if mode.shades_pixels() {
                if gi.trace.gathers() {
                    steps.push(Step::Gather);
                }
                steps.push(Step::Trace);
                if gi.trace.gathers() {
                    steps.push(Step::TraceUnmatched);
                }
            } else {
                steps.push(Step::VoxelView);
            }
        }
        if self.accumulate.is_some() && mode.shades_pixels() {
            steps.push(Step::Accumulate);
        }
        if readback {
            steps.push(Step::Readback);
        }
        steps
    }

    /// The steps the next frame records.
    pub fn steps(&self, readback: bool) -> Vec<Step> {
        let voxels = self.gi.as_ref().map_or(Dirty::NONE, |gi| gi.dirty);
        self.steps_when(self.shadows.any_dirty(), voxels, readback)
    }

    /// The passes of `voxgi render`'s first frame, in order, by the names their debug labels
    /// and `--timings` give them: every shadow view is drawn, the voxels made and lit; later
    /// frames record only what changed (a still frame: the G-buffer, lighting and trace), and
    /// the last one the readback.
    pub fn passes(&self) -> Vec<String> {
        let shadows = self.gpu.shadow_view_count > 0;
        self.steps_when(shadows, Dirty::ALL, true)
            .iter()
            .map(Step::name)
            .collect()
    }

    /// What drawing the scene takes.
    fn scene(&self) -> SceneDraw<'_> {
        SceneDraw {
            instances: &self.instances,
            gpu: &self.gpu,
            sets: &self.sets,
        }
    }

    fn record_step(&self, g: &mut Graph, step: Step) {
        let ctx = &self.ctx;
        let name = step.name();
        let targets = &self.targets;
        match step {
            Step::Shadows => {
                // An area light's own faces would hide it (its centre may be inside).
                let hides = |i: usize, view: u32| {
                    self.area_light_of[i].is_some_and(|k| {
                        let v = &self.gpu.light_views[self.lights.len() + k];
                        (v.first..v.first + v.views.len() as u32).contains(&view)
                    })
                };
                self.shadows.record(ctx, g, &name, &self.scene(), hides)
            }
            Step::Voxels(s) => self.record_voxels(g, s),
            Step::GBuffer => self.gbuffer.record(ctx, g, &name, targets, &self.scene()),
            Step::Lighting => {
                let scene_set = self.sets.scene_set();
                self.lighting.record(ctx, g, &name, targets, scene_set)
            }
            Step::AreaFaces => {
                let scene_set = self.sets.scene_set();
                self.lighting.record_faces(ctx, g, &name, scene_set)
            }
            Step::Gather => self.record_gather(g, &name),
            Step::Trace | Step::VoxelView => self.record_trace(g, &name),
            Step::TraceUnmatched => self.record_trace_unmatched(g, &name),
            Step::Accumulate => {
                if let Some(a) = &self.accumulate {
                    let w = accumulate::weight(self.mean_frames, self.settings.accumulate);
                    a.record(ctx, g, &name, targets, w);
                }
            }
            Step::Readback => targets.record_readback(ctx, g, &name),
        }
    }

    /// One voxel step; voxelization draws the instances of its kind (static or dynamic).
    fn record_voxels(&self, g: &mut Graph, step: crate::gi::Step) {
        let Some(gi) = &self.gi else {
            return;
        };
        let scene = self.scene();
        let draw = |dynamic: bool| {
            let (scene, list) = (&scene, self.instances.of_kind(dynamic));
            move |cmd: vk::CommandBuffer, p: &Pipeline, flags: u32, range: Range<usize>| unsafe {
                let extra = |i: usize| {
                    let light = self.area_light_of[i].map_or(0, |_| crate::gi::EMITTER_LIGHT);
                    self.instances.mirrored(i) | flags | light
                };
                scene.draw(&self.ctx.device, cmd, p, extra, list[range].iter().copied())
            }
        };
        let (draw_static, draw_dynamic) = (draw(false), draw(true));
        let inputs = StepInputs {
            geometry: (&self.gpu.vertices, &self.gpu.indices),
            scene_set: self.sets.scene_set(),
            draw_static: VoxelDraws {
                count: self.instances.of_kind(false).len(),
                draw: &draw_static,
            },
            draw_dynamic: VoxelDraws {
                count: self.instances.of_kind(true).len(),
                draw: &draw_dynamic,
            },
        };
        gi.record_step(&self.ctx, g, step, &inputs);
    }

    /// Cones per pixel, or the first voxel along each camera ray (the voxel modes).
    fn record_trace(&self, g: &mut Graph, name: &str) {
        let Some(gi) = &self.gi else {
            return;
        };
        let size = (self.targets.width, self.targets.height);
        gi.trace.record(
            &self.ctx,
            g,
            self.sets.scene_set(),
            size,
            self.trace_mode(),
            name,
        );
    }

    /// The pixels the trace left to a pass of their own.
    fn record_trace_unmatched(&self, g: &mut Graph, name: &str) {
        let Some(gi) = &self.gi else {
            return;
        };
        let mode = self.trace_mode();
        gi.trace
            .record_unmatched(&self.ctx, g, self.sets.scene_set(), mode, name);
    }

    /// What the trace pass writes in the renderer's mode.
    fn trace_mode(&self) -> TraceMode {
        match self.settings.mode {
            Mode::Full => TraceMode::Full,
            Mode::Indirect => TraceMode::Indirect,
            Mode::Ao => TraceMode::Ao,
            Mode::VoxelsAlbedo => TraceMode::VoxelAlbedo,
            Mode::VoxelsNormal => TraceMode::VoxelNormal,
            Mode::VoxelsEmission => TraceMode::VoxelEmission,
            Mode::VoxelsRadiance if self.settings.mip.is_some() => TraceMode::Directional,
            Mode::VoxelsRadiance => TraceMode::VoxelRadiance,
            Mode::Direct => unreachable!("direct mode has no voxel passes"),
        }
    }

    /// The diffuse cones per block or over frames, before the trace.
    fn record_gather(&self, g: &mut Graph, name: &str) {
        let Some(gi) = &self.gi else {
            return;
        };
        let time = TraceFrame {
            prev_view_proj: self.prev_view_proj,
            index: self.history_frames,
            // At rest with the refresh done, the antialiasing mean's count, as after a fresh
            // start: the frames after a stop then trace what a fresh start's frames trace.
            subset: if self.still && self.refresh_left == 0 {
                u64::from(self.mean_frames)
            } else {
                self.history_frames
            },
            reset: self.history_reset,
            still: self.still,
        };
        gi.trace
            .record_gather(&self.ctx, g, self.sets.scene_set(), &time, name);
    }

    /// Frames the temporal trace takes to trace the whole cone set by subsets (0: none).
    fn temporal_subsets(&self) -> u32 {
        self.gi
            .as_ref()
            .filter(|gi| gi.trace.gathers())
            .map_or(0, |gi| gi.trace.layout.temporal)
    }

    /// The next frame traces the diffuse cones afresh, without the temporal history: a camera
    /// cut (a new view that shares surfaces with the old one would otherwise reuse their
    /// light, which is right but not what a first frame shows).
    pub fn discard_history(&mut self) {
        self.history_reset = true;
    }

    /// Moves every instance of a glTF node: the next frame voxelizes again the geometry of
    /// its kind (dynamic or static), lights the voxels again and draws again the shadow views
    /// it moves through. Setting the transform it has changes nothing.
    pub fn set_node_transform(&mut self, node: usize, world: Mat4) {
        let moved = self.instances.move_node(node, world);
        if !moved.is_empty() {
            self.mean_frames = 0;
        }
        for m in &moved {
            // Where it was and where it goes: the views that see either draw again.
            let views = self.gpu.light_views.iter().flat_map(|l| &l.views);
            for (dirty, v) in self.shadows.dirty.iter_mut().zip(views) {
                *dirty |= super::shadows::may_see(&v.view_proj, &m.swept);
            }
        }
        if let Some(gi) = self.gi.as_mut() {
            gi.dirty.static_voxels |= moved.iter().any(|m| !m.dynamic);
            gi.dirty.dynamic_voxels |= moved.iter().any(|m| m.dynamic);
        }
        // An area light goes with its faces: its views draw again and the voxels are lit
        // again.
        let mut moved_light = false;
        for k in 0..self.area_lights.len() {
            if moved
                .iter()
                .any(|m| m.instance == self.area_lights[k].instance)
            {
                self.area_lights[k].place(&world);
                let v = &self.gpu.light_views[self.lights.len() + k];
                let views = v.first as usize..v.first as usize + v.views.len();
                self.shadows.dirty[views].fill(true);
                moved_light = true;
            }
        }
        if moved_light {
            self.write_lights();
            if let Some(gi) = self.gi.as_mut() {
                gi.dirty.lights = true;
            }
        }
    }

    /// The emissive surfaces lit as area lights.
    pub fn area_lights(&self) -> &[AreaLight] {
        &self.area_lights
    }

    /// Writes the lights and their shadow views (the scene's and the area lights') for the next
    /// frame; the previous frame was waited for, so nothing on the GPU reads them now.
    fn write_lights(&mut self) {
        let table = light_table(
            &self.lights,
            &self.area_lights,
            &self.bounds,
            self.settings.shadow_resolutions(),
            self.settings.pcf_radius,
        );
        self.gpu.lights.write(&table);
        self.gpu.light_views = table.views;
    }

    /// A new frame size: the frame's targets are made again at the new size; the scene, the
    /// shadow maps and the voxels stay (no voxelization again).
    pub fn resize(&mut self, width: u32, height: u32) -> VkResult<()> {
        if (width, height) == (self.settings.width, self.settings.height) {
            return Ok(());
        }
        let targets = FrameTargets::new(&self.ctx, width, height, self.accumulate.is_some())?;
        // Every frame before was waited for: the sets are not in use.
        self.lighting.retarget(
            &self.ctx,
            &self.sets,
            &LightingInputs {
                targets: &targets,
                nearest: &self.nearest,
                shadow: &self.shadows,
                voxels: faces_voxels(self.gi.as_ref(), self.area_lights.len()),
            },
            &mut self.states,
        )?;
        if let Some(a) = &mut self.accumulate {
            a.retarget(&self.ctx, &targets)?;
        }
        if let Some(gi) = &mut self.gi {
            let frame = FrameImages {
                size: (width, height),
                gbuffer: &targets.gbuffer,
                sampler: self.nearest.raw,
                out: &targets.hdr,
            };
            gi.trace.retarget(
                &self.ctx,
                &self.sets.scene,
                &gi.volumes,
                &frame,
                &mut self.states,
            )?;
        }
        self.discard_history();
        self.targets.forget(&mut self.states);
        self.targets = targets;
        self.settings.width = width;
        self.settings.height = height;
        Ok(())
    }

    /// Moves or changes the lights (one per scene light, each of its kind as loaded, so the
    /// shadow views keep their number; the environment's sun stays as it is): the next frame
    /// draws their shadow maps and lights the voxels with them.
    pub fn set_lights(&mut self, lights: &[Light]) -> VkResult<()> {
        use super::shadows::light_views;
        let mut lights = lights.to_vec();
        if self.env_sun.is_some() {
            lights.extend(self.lights.last().cloned());
        }
        let lights = &lights[..];
        let views = light_views(
            lights,
            &self.bounds,
            self.settings.shadow_resolution,
            self.settings.pcf_radius,
        );
        let counts: Vec<usize> = views.iter().map(|v| v.views.len()).collect();
        let before: Vec<usize> = self.gpu.light_views[..self.lights.len()]
            .iter()
            .map(|v| v.views.len())
            .collect();
        if lights.len() != self.lights.len() || counts != before {
            return Err(VkError::Request(
                "set_lights: the lights must keep their number and kinds".into(),
            ));
        }
        self.lights = lights.to_vec();
        self.write_lights();
        self.relight();
        Ok(())
    }

    /// The environment's strength (None without an environment).
    pub fn environment_strength(&self) -> Option<f32> {
        (self.environment.w > 0.0).then(|| self.environment.x / self.environment_texel_scale)
    }

    /// Scales the environment's radiance by `strength` (its `--env-strength`; nothing without
    /// an environment). The voxels are lit again, as after a light moved: their bounce gathers
    /// it.
    pub fn set_environment_strength(&mut self, strength: f32) {
        if self.environment.w > 0.0 && self.environment_strength() != Some(strength) {
            self.environment.x = strength * self.environment_texel_scale;
            self.history_reset = true;
            if let (Some(sun), Some(last)) = (&self.env_sun, self.lights.last_mut()) {
                last.radiance = sun.radiance * strength;
                self.write_lights();
            }
            self.relight();
        }
    }

    /// The next frame draws every shadow map and lights the voxels again (bounces included),
    /// as after a light moved; the benchmark times such frames.
    pub fn relight(&mut self) {
        self.shadows.dirty.fill(true);
        if let Some(gi) = self.gi.as_mut() {
            gi.dirty.lights = true;
        }
    }

    /// Entries in the frame-time list and the pass timer's lists together (bounded: see
    /// [`crate::vk::timing::TIMED_FRAMES`]).
    pub fn timing_entries(&self) -> usize {
        self.frame_ms.len()
            + self
                .timer
                .as_ref()
                .map_or(0, |t| t.samples.iter().map(|s| s.1.len()).sum())
    }

    /// Debug readback of the voxel volumes as the last frame left them (None in direct mode).
    pub fn read_voxels(&mut self) -> VkResult<Option<crate::gi::VoxelDump>> {
        match &self.gi {
            Some(gi) => Ok(Some(gi.read_voxels(&self.ctx, &mut self.states)?)),
            None => Ok(None),
        }
    }

    /// Non-finite values in the lit volumes as the last frame left them, one level at a time
    /// (None in direct mode).
    pub fn count_non_finite(&mut self) -> VkResult<Option<crate::gi::NonFinite>> {
        match &self.gi {
            Some(gi) => Ok(Some(gi.count_non_finite(&self.ctx, &mut self.states)?)),
            None => Ok(None),
        }
    }

    /// Linear radiance, RGB per pixel, row 0 at the top (after `render(true)`).
    pub fn radiance(&self) -> Vec<[f32; 3]> {
        self.targets.radiance()
    }

    /// The frame's linear radiance (RGBA32F, storage in GENERAL), for passes that follow.
    pub fn radiance_image(&self) -> &Image {
        &self.targets.hdr
    }

    pub fn context(&self) -> &Arc<Context> {
        &self.ctx
    }
}

/// The emissive surfaces lit as area lights: where the pixels are shaded and the voxels lit
/// (the views of the voxels' materials show every emitter's emission) or in direct mode, never
/// for --paper.
fn area_lights_of(scene: &Scene, settings: &RenderSettings) -> Vec<AreaLight> {
    let gi = &settings.gi;
    let mode = settings.mode;
    if (mode.lights_voxels() || mode == Mode::Direct) && gi.area_lights && !gi.paper {
        area_lights::find(scene)
    } else {
        Vec::new()
    }
}

/// The G-buffer's sampler: texel for texel.
fn nearest_sampler(ctx: &Arc<Context>) -> VkResult<Sampler> {
    Sampler::new(
        ctx,
        &vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE),
    )
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // The fields free themselves after this, once the device has finished with them.
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
        }
    }
}

/// The voxels the area lights' faces pass reads (lighting.rs): where there are area lights and
/// the voxels are the default's (not --paper's RGBA8 averages).
fn faces_voxels(gi: Option<&Gi>, area_lights: usize) -> Option<&crate::gi::Volumes> {
    gi.filter(|g| area_lights > 0 && !g.settings.paper)
        .map(|g| &g.volumes)
}
