//! The hard cases, each a scene, a measurement and a goal.

use super::scenes::*;
use super::{max, mean, node_of, rel_mse, scaled, Case, Env, Goal};
use crate::gi::GiSettings;
use crate::render::Mode;
use crate::scene::builder::*;
use crate::scene::Environment;
use anyhow::{ensure, Result};
use glam::{DVec3, Mat4, Vec3};

/// The error against the reference that counts as a working render of a small test scene
/// (the Cornell box at the defaults: about 0.005).
const REF_GOAL: Goal = Goal::AtMost(0.05);
/// Two renders of what must be the same image.
const SAME_GOAL: Goal = Goal::AtMost(0.001);
/// The open rooms' references take four times the samples: their insides are lit only by light
/// that bounced, and at 64x64 and 256 spp the path tracer's own noise was a quarter of the goal
/// (sky-room 0.0207 against 256 spp, 0.0163 against 1024, 0.0149 against 4096).
const ROOM_SPP: u32 = 4;

pub static CASES: &[Case] = &[
    Case {
        name: "leak-wall-0",
        group: "light leaking",
        what: "two closed rooms split by a zero-thickness wall, a point light in one; mean \
               radiance seen in the dark room over that in the lit room, the larger of the \
               wall on a voxel boundary and 2 cm off it (its faces in one voxel)",
        metric: "leak ratio",
        goal: Goal::AtMost(0.01),
        run: |env, gi| leak(env, gi, 0, 0.0, RoomsLight::Point),
    },
    Case {
        name: "leak-wall-1cm",
        group: "light leaking",
        what: "the same with a 1 cm wall",
        metric: "leak ratio",
        goal: Goal::AtMost(0.01),
        run: |env, gi| leak(env, gi, 0, 0.01, RoomsLight::Point),
    },
    Case {
        name: "leak-floor-1cm",
        group: "light leaking",
        what: "a room over a lit room, a 1 cm floor between",
        metric: "leak ratio",
        goal: Goal::AtMost(0.01),
        run: |env, gi| leak(env, gi, 1, 0.01, RoomsLight::Point),
    },
    Case {
        name: "leak-wall-bounce",
        group: "light leaking",
        what: "leak-wall-0 lit by an emissive square facing the wall instead, with at least 2 \
               bounces: the wall's voxels hold only bounced light",
        metric: "leak ratio",
        goal: Goal::AtMost(0.01),
        run: |env, gi| {
            let gi = GiSettings {
                bounces: gi.bounces.max(2),
                ..gi.clone()
            };
            leak(env, &gi, 0, 0.0, RoomsLight::Emitter(5.0))
        },
    },
    Case {
        name: "leak-junction",
        group: "light leaking",
        what: "two 3 x 2.5 x 4 m rooms sharing their floor, ceiling and side walls, split by a \
               zero-thickness divider whose edges go 1 cm into them, a 20 W/sr point light 30 \
               cm from it; the worst of the divider on a voxel boundary, 2 cm and half a voxel \
               off it",
        metric: "leak ratio",
        goal: Goal::AtMost(0.01),
        run: junction_leak,
    },
    Case {
        name: "door-room",
        group: "light leaking",
        what: "leak-junction's rooms with a door 1 m wide and 2 m high in the divider, seen \
               from the room the light reaches through it; relMSE against the reference, the \
               worst of the divider on a voxel boundary and 2 cm off it",
        metric: "relMSE",
        goal: Goal::AtMost(0.05),
        run: |env, gi| {
            let mut worst = 0.0f64;
            for offset in [0.0, 0.02] {
                let (b, _, dark_cam) = junction_rooms(offset, true);
                let s = env.load("door", &b)?;
                worst = worst.max(env.error_vs_reference(&s, &dark_cam, gi)?);
            }
            Ok(worst)
        },
    },
    Case {
        name: "density-300",
        group: "density",
        what: "300 overlapping triangles in one voxel; largest relative error of a voxel's \
               averaged albedo",
        metric: "albedo error",
        goal: Goal::AtMost(0.02),
        run: |env, gi| density(env, gi, 300),
    },
    Case {
        name: "density-3000",
        group: "density",
        what: "3000 overlapping triangles in one voxel",
        metric: "albedo error",
        goal: Goal::AtMost(0.02),
        run: |env, gi| density(env, gi, 3000),
    },
    Case {
        name: "two-sided-panel",
        group: "density",
        what: "a thin two-sided panel (opposite normals in one voxel) lit from one side, seen \
               from the other; relMSE against the reference",
        metric: "relMSE",
        goal: REF_GOAL,
        run: two_sided_panel,
    },
    Case {
        name: "scale-1mm",
        group: "scale and precision",
        what: "a room scaled to 1 mm (camera and lights too); relMSE against the 1 m image",
        metric: "relMSE",
        goal: SAME_GOAL,
        run: |env, gi| transformed_room(env, gi, 0.001, DVec3::ZERO, RoomLight::Point(2.0)),
    },
    Case {
        name: "scale-10km",
        group: "scale and precision",
        what: "the room scaled to 10 km",
        metric: "relMSE",
        goal: SAME_GOAL,
        run: |env, gi| transformed_room(env, gi, 1e4, DVec3::ZERO, RoomLight::Point(2.0)),
    },
    Case {
        name: "translated-1e5",
        group: "scale and precision",
        what: "the room translated 1e5 m from the origin",
        metric: "relMSE",
        goal: SAME_GOAL,
        run: |env, gi| {
            transformed_room(
                env,
                gi,
                1.0,
                DVec3::new(1e5, 0.0, 0.0),
                RoomLight::Point(2.0),
            )
        },
    },
    Case {
        name: "near-light-1e5",
        group: "scale and precision",
        what: "the room with its point light 5 cm under the ceiling, translated by (1e5 + 0.35, \
               0, 1e5 + 0.35) m (not a float's value: read as f32 the node would move 1.6 mm)",
        metric: "relMSE",
        goal: SAME_GOAL,
        run: |env, gi| {
            let offset = DVec3::new(1e5 + 0.35, 0.0, 1e5 + 0.35);
            transformed_room(env, gi, 1.0, offset, RoomLight::PointNearCeiling(0.5))
        },
    },
    Case {
        name: "near-light-1e6",
        group: "scale and precision",
        what: "the same translated by (1e6 + 0.35, 0, 1e6 + 0.35) m",
        metric: "relMSE",
        goal: Goal::AtMost(0.01),
        run: |env, gi| {
            let offset = DVec3::new(1e6 + 0.35, 0.0, 1e6 + 0.35);
            transformed_room(env, gi, 1.0, offset, RoomLight::PointNearCeiling(0.5))
        },
    },
    Case {
        name: "rotated-1e-6",
        group: "scale and precision",
        what: "the room and camera turned 1e-6 rad about the vertical, either way (the walls \
               facing x get normals with a tiny z of either sign); the larger relMSE",
        metric: "relMSE",
        goal: SAME_GOAL,
        run: |env, gi| Ok(rotated_room(env, gi, 1e-6)?.max(rotated_room(env, gi, -1e-6)?)),
    },
    Case {
        name: "degenerate",
        group: "degenerate input",
        what: "the room plus zero-area, sliver and repeated-vertex triangles, NaN and Inf \
               positions and normals, zero-length normals; relMSE against the clean room",
        metric: "relMSE",
        goal: SAME_GOAL,
        run: degenerate,
    },
    Case {
        name: "light-zero",
        group: "lights",
        what: "the room lit only by a point light of intensity 0; largest pixel",
        metric: "max radiance",
        goal: Goal::AtMost(0.0),
        run: |env, gi| {
            let (b, cam) = room(RoomLight::Point(0.0));
            let s = env.load("light-zero", &b)?;
            Ok(max(&env.render(&s, &cam, gi)?))
        },
    },
    Case {
        name: "light-1e6",
        group: "lights",
        what: "a point light of 1e6 W/sr; relMSE of the image / 1e6 against the image at 1 W/sr",
        metric: "relMSE",
        goal: SAME_GOAL,
        run: |env, gi| {
            let (b, cam) = room(RoomLight::Point(1e6));
            let s = env.load("light-1e6", &b)?;
            let strong = env.render(&s, &cam, gi)?;
            let (b, cam) = room(RoomLight::Point(1.0));
            let s = env.load("light-1", &b)?;
            let unit = env.render(&s, &cam, gi)?;
            Ok(rel_mse(&scaled(&strong, 1e-6), &unit))
        },
    },
    Case {
        name: "light-inside-geometry",
        group: "lights",
        what: "a second point light inside a closed box; relMSE against the room without it",
        metric: "relMSE",
        goal: SAME_GOAL,
        run: light_inside,
    },
    Case {
        name: "spot-hard-edge",
        group: "lights",
        what: "a spot with inner = outer cone angle; relMSE against the reference",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let a = 30f32.to_radians();
            let (b, cam) = room(RoomLight::Spot(a, a));
            let s = env.load("spot", &b)?;
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "sun-along-axis",
        group: "lights",
        what: "a directional light exactly along -Y; relMSE against the reference",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let (b, cam) = yard(Vec3::NEG_Y);
            let s = env.load("sun-axis", &b)?;
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "sun-grazing",
        group: "lights",
        what: "a directional light 1 degree above the horizon",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let el = 1f32.to_radians();
            let (b, cam) = yard(Vec3::new(-el.cos(), -el.sin(), 0.3).normalize());
            let s = env.load("sun-grazing", &b)?;
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "emissive-1e4",
        group: "emission",
        what: "the room lit only by a 2 cm emitter of strength 1e4; relMSE against the \
               reference",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let (b, cam) = room(RoomLight::Panel {
                strength: 1e4,
                side: 0.02,
            });
            let s = env.load("emissive-1e4", &b)?;
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "area-cornell",
        group: "emission",
        what: "the classic Cornell box lit only by its 13 x 10.5 cm two-sided ceiling quad; \
               relMSE against the reference",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let (b, cam) = cornell_quad_light();
            let s = env.load("area-cornell", &b)?;
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "area-room",
        group: "emission",
        what: "a 4 x 2.5 x 4 m room lit only by two emissive spheres and two cubes 15 to 25 \
               cm across; relMSE against the reference",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let (b, cam) = emitter_room();
            let s = env.load("area-room", &b)?;
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "emissive-dynamic",
        group: "emission",
        what: "an emissive box that moves (dynamic voxels); relMSE against a static render \
               of where it ends",
        metric: "relMSE",
        goal: SAME_GOAL,
        run: emissive_dynamic,
    },
    Case {
        name: "grazing-surfaces",
        group: "cones",
        what: "a camera 2 cm over the floor looking along it; relMSE against the reference",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let (b, _) = yard(Vec3::new(-1.0, -1.0, -0.5));
            let s = env.load("grazing", &b)?;
            let cam = look_at(
                Vec3::new(1.9, 0.02, 1.9),
                Vec3::new(-1.0, 0.02, -1.0),
                50.0,
                0.005,
            );
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "cones-leave-grid",
        group: "cones",
        what: "an open yard (cones leave the grid for the black sky); relMSE against the \
               reference",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let (b, cam) = yard(Vec3::new(-1.0, -1.0, -0.5));
            let s = env.load("yard", &b)?;
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "sky-yard",
        group: "environment",
        what: "the open yard under its sun and a uniform sky (0.3, 0.45, 0.8); relMSE against \
               the reference",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let (b, cam) = yard(Vec3::new(-1.0, -1.0, -0.5));
            let mut s = env.load("yard", &b)?;
            s.environment = Some(Environment::uniform(Vec3::new(0.3, 0.45, 0.8)));
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "sky-room",
        group: "environment",
        what: "a 4 x 2.5 x 4 m room open on one side under a uniform sky, its walls facing \
               in; relMSE against the reference (four times the samples)",
        metric: "relMSE",
        goal: Goal::AtMost(0.02),
        run: |env, gi| {
            let (b, cam) = open_room(false);
            let mut s = env.load("open-room", &b)?;
            s.environment = Some(Environment::uniform(Vec3::ONE));
            env.with_more_samples(ROOM_SPP, |env| env.error_vs_reference(&s, &cam, gi))
        },
    },
    Case {
        name: "sky-room-outward",
        group: "environment",
        what: "the same room, its walls single quads facing out (lit on their backs inside); \
               relMSE against the reference (four times the samples)",
        metric: "relMSE",
        goal: Goal::AtMost(0.02),
        run: |env, gi| {
            let (b, cam) = open_room(true);
            let mut s = env.load("open-room-outward", &b)?;
            s.environment = Some(Environment::uniform(Vec3::ONE));
            env.with_more_samples(ROOM_SPP, |env| env.error_vs_reference(&s, &cam, gi))
        },
    },
    Case {
        name: "camera-in-volume",
        group: "cones",
        what: "the camera at the middle of the room (inside the grid)",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let (b, _) = room(RoomLight::Point(2.0));
            let s = env.load("room", &b)?;
            let cam = look_at(
                Vec3::new(0.0, 1.0, 0.9),
                Vec3::new(0.0, 0.9, -1.0),
                70.0,
                0.01,
            );
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "camera-in-voxel",
        group: "cones",
        what: "the camera 5 mm from the back wall (inside its voxel), looking out",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let (b, _) = room(RoomLight::Point(2.0));
            let s = env.load("room", &b)?;
            let cam = look_at(
                Vec3::new(0.0, 1.0, -0.995),
                Vec3::new(0.0, 0.7, 1.0),
                70.0,
                0.001,
            );
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "grid-48",
        group: "cones",
        what: "the room on a 48^3 grid (not a power of two)",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| room_at(env, gi, 48),
    },
    Case {
        name: "grid-100",
        group: "cones",
        what: "the room on a 100^3 grid",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| room_at(env, gi, 100),
    },
    Case {
        name: "grid-8",
        group: "cones",
        what: "the room on an 8^3 grid",
        metric: "relMSE",
        goal: Goal::AtMost(0.1),
        run: |env, gi| room_at(env, gi, 8),
    },
    Case {
        name: "grid-512",
        group: "cones",
        what: "the room on a 512^3 grid",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| room_at(env, gi, 512),
    },
    Case {
        name: "empty-scene",
        group: "trivial",
        what: "a scene with nothing in it; largest pixel",
        metric: "max radiance",
        goal: Goal::AtMost(0.0),
        run: |env, gi| {
            let s = env.load("empty", &SceneBuilder::new())?;
            let cam = look_at(Vec3::Z, Vec3::ZERO, 40.0, 0.01);
            Ok(max(&env.render(&s, &cam, gi)?))
        },
    },
    Case {
        name: "single-triangle",
        group: "trivial",
        what: "one triangle under a directional light; relMSE against the reference",
        metric: "relMSE",
        goal: REF_GOAL,
        run: |env, gi| {
            let mut b = SceneBuilder::new();
            let m = b.add_material(MaterialDesc::lambertian("white", WHITE));
            let t = b.add_triangles(
                "triangle",
                &[[-1.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 0.0, -1.0]],
                None,
                Some(m),
            );
            b.add_node(NodeDesc::new("triangle").mesh(t));
            add_sun(&mut b, Vec3::new(-0.3, -1.0, -0.2), 3.0);
            let s = env.load("triangle", &b)?;
            let cam = look_at(Vec3::new(0.0, 2.0, 2.0), Vec3::ZERO, 60.0, 0.01);
            env.error_vs_reference(&s, &cam, gi)
        },
    },
    Case {
        name: "no-light",
        group: "trivial",
        what: "the room with no light and no emission; largest pixel",
        metric: "max radiance",
        goal: Goal::AtMost(0.0),
        run: |env, gi| {
            let (b, cam) = room(RoomLight::None);
            let s = env.load("dark", &b)?;
            Ok(max(&env.render(&s, &cam, gi)?))
        },
    },
    Case {
        name: "furnace",
        group: "trivial",
        what: "a closed box of albedo 0.5 emitting Le = 1 everywhere; relative error of the \
               mean radiance against Le / (1 - albedo) = 2",
        metric: "relative error",
        goal: Goal::AtMost(0.05),
        run: |env, gi| {
            let (b, cam) = furnace(0.5, 1.0);
            let s = env.load("furnace", &b)?;
            let img = env.render(&s, &cam, gi)?;
            env.measure_ideal(&s, &cam, gi, &img, |ideal| (mean(ideal) / 2.0 - 1.0).abs())?;
            Ok((mean(&img) / 2.0 - 1.0).abs())
        },
    },
];

fn leak(
    env: &mut Env,
    gi: &GiSettings,
    axis: usize,
    thickness: f32,
    light: RoomsLight,
) -> Result<f64> {
    // The worse of two places for the partition: on a voxel boundary, and inside a voxel (its
    // two faces in one voxel, which a cone beside its dark face reads).
    let mut worst = 0.0f64;
    for offset in [0.0, 0.02] {
        let (b, lit_cam, dark_cam) = two_rooms(axis, thickness, light, offset);
        let s = env.load("rooms", &b)?;
        let lit = mean(&env.render(&s, &lit_cam, gi)?);
        let dark = mean(&env.render(&s, &dark_cam, gi)?);
        ensure!(lit > 0.0, "the lit room is black");
        worst = worst.max(dark / lit);
    }
    Ok(worst)
}

fn junction_leak(env: &mut Env, gi: &GiSettings) -> Result<f64> {
    let mut worst = 0.0f64;
    for offset in [0.0, 0.02, 0.048] {
        let (b, lit_cam, dark_cam) = junction_rooms(offset, false);
        let s = env.load("junction", &b)?;
        let lit = mean(&env.render(&s, &lit_cam, gi)?);
        let dark = mean(&env.render(&s, &dark_cam, gi)?);
        ensure!(lit > 0.0, "the lit room is black");
        worst = worst.max(dark / lit);
    }
    Ok(worst)
}

fn density(env: &mut Env, gi: &GiSettings, n: usize) -> Result<f64> {
    let mut b = SceneBuilder::new();
    let floor_m = b.add_material(MaterialDesc::lambertian("floor", [0.2, 0.2, 0.2]));
    let albedo = [0.9, 0.5, 0.1];
    let stack_m = b.add_material(MaterialDesc::lambertian("stack", albedo));
    let floor = quad(
        [
            [-1.0, 0.0, -1.0],
            [1.0, 0.0, -1.0],
            [1.0, 0.0, 1.0],
            [-1.0, 0.0, 1.0],
        ],
        [0.0, 1.0, 0.0],
        Some(floor_m),
    );
    // n small triangles turned about a common point 1 m above the floor, all within 5 mm.
    let mut positions = Vec::with_capacity(3 * n);
    for i in 0..n {
        let a = i as f32 * 2.399963; // golden angle
        let (s, c) = a.sin_cos();
        let r = 0.004;
        for k in 0..3 {
            let t = k as f32 * 2.0944;
            let (ts, tc) = t.sin_cos();
            positions.push([r * tc * c, 1.0 + r * ts, r * tc * s]);
        }
    }
    let mut stack = PrimitiveDesc::triangles(&positions, Some(stack_m));
    stack.normals = None;
    let mesh = b.add_mesh("scene", vec![floor, stack]);
    b.add_node(NodeDesc::new("scene").mesh(mesh));
    add_sun(&mut b, Vec3::new(0.2, -1.0, 0.1), 3.0);
    let s = env.load("density", &b)?;
    let cam = look_at(
        Vec3::new(0.0, 1.5, 2.0),
        Vec3::new(0.0, 0.5, 0.0),
        40.0,
        0.01,
    );
    let mut worst = 0.0f64;
    let mut found = 0;
    let settings = crate::render::RenderSettings {
        width: env.size,
        height: env.size,
        shadow_resolution: 512,
        gi: gi.clone(),
        ..Default::default()
    };
    let mut r = crate::render::Renderer::new(&env.ctx, &s, settings)?;
    r.camera = cam;
    r.render(true)?;
    let v = r.read_voxels()?.expect("full mode lights voxels");
    let n = v.resolution;
    let grid = r.gi.as_ref().expect("full mode has voxels").volumes.grid;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let i = v.index(x, y, z);
                let centre = grid.origin
                    + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * grid.size / n as f32;
                if !v.filled[i] || centre.y < 0.5 {
                    continue;
                }
                found += 1;
                let a = v.albedo[i];
                let want = Vec3::from(albedo);
                worst = worst.max(((a - want).abs() / want).max_element() as f64);
                if !a.is_finite() {
                    worst = f64::INFINITY;
                }
            }
        }
    }
    ensure!(found > 0, "the stack of triangles left no voxel");
    Ok(worst)
}

fn two_sided_panel(env: &mut Env, gi: &GiSettings) -> Result<f64> {
    let (mut b, _) = yard(Vec3::new(-1.0, -0.8, 0.2));
    let m = b.add_material(MaterialDesc {
        double_sided: true,
        ..MaterialDesc::lambertian("panel", WHITE)
    });
    let panel = quad(
        [
            [0.0, 0.0, -1.5],
            [0.0, 0.0, 1.5],
            [0.0, 1.5, 1.5],
            [0.0, 1.5, -1.5],
        ],
        [1.0, 0.0, 0.0],
        Some(m),
    );
    let mesh = b.add_mesh("panel", vec![panel]);
    b.add_node(
        NodeDesc::new("panel")
            .mesh(mesh)
            .translation([-1.2, 0.0, 0.0]),
    );
    let s = env.load("panel", &b)?;
    // From the shaded side of the panel.
    let cam = look_at(
        Vec3::new(-2.0, 1.0, 0.8),
        Vec3::new(-1.2, 0.6, 0.0),
        60.0,
        0.01,
    );
    env.error_vs_reference(&s, &cam, gi)
}

fn transformed_room(
    env: &mut Env,
    gi: &GiSettings,
    scale: f32,
    offset: DVec3,
    light: RoomLight,
) -> Result<f64> {
    let (b, cam) = room(light);
    let s = env.load("room", &b)?;
    let base = env.render(&s, &cam, gi)?;
    let t = transformed(&b, scale, offset);
    let s = env.load("room-transformed", &t)?;
    let img = env.render(&s, &transform_camera(&cam, scale, offset, s.origin), gi)?;
    Ok(rel_mse(&img, &base))
}

fn rotated_room(env: &mut Env, gi: &GiSettings, angle: f32) -> Result<f64> {
    let (b, cam) = room(RoomLight::Point(2.0));
    let s = env.load("room", &b)?;
    let base = env.render(&s, &cam, gi)?;
    let q = glam::Quat::from_rotation_y(angle);
    let mut t = b.clone();
    t.wrap_roots(NodeDesc::new("root").rotation(q.to_array()));
    let s = env.load("room-rotated", &t)?;
    let turned = crate::scene::Camera {
        world: Mat4::from_quat(q) * cam.world,
        ..cam.clone()
    };
    let img = env.render(&s, &turned, gi)?;
    Ok(rel_mse(&img, &base))
}

fn degenerate(env: &mut Env, gi: &GiSettings) -> Result<f64> {
    let (b, cam) = room(RoomLight::Point(2.0));
    let s = env.load("room", &b)?;
    let clean = env.render(&s, &cam, gi)?;
    let mut d = b.clone();
    let m = d.add_material(MaterialDesc::lambertian("junk", [0.9, 0.1, 0.9]));
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let positions = vec![
        // Zero area: one point three times.
        [0.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        // Collinear.
        [-0.5, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.5, 1.0, 0.0],
        // NaN and Inf positions.
        [nan, 1.0, 0.0],
        [0.5, 1.5, 0.0],
        [0.0, 1.5, 0.5],
        [0.2, inf, 0.0],
        [0.5, 1.5, 0.0],
        [0.0, 1.5, 0.5],
    ];
    let junk = PrimitiveDesc::triangles(&positions, Some(m));
    // A floor patch with NaN, Inf and zero-length normals, lying on the floor: the loader
    // replaces the normals with the face normal (+Y), the same as the floor's.
    let floor_m = d.add_material(MaterialDesc::lambertian("white", WHITE));
    let patch = PrimitiveDesc {
        positions: vec![
            [-0.9, 0.0, 0.9],
            [-0.5, 0.0, 0.9],
            [-0.5, 0.0, 0.5],
            [-0.9, 0.0, 0.5],
        ],
        normals: Some(vec![
            [nan, 1.0, 0.0],
            [0.0, inf, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ]),
        uvs: None,
        // Repeated vertices and a repeated triangle.
        indices: Some(vec![0, 1, 2, 0, 2, 3, 0, 2, 3, 1, 1, 1]),
        material: Some(floor_m),
    };
    // A sliver 1e-7 m wide.
    let sliver = PrimitiveDesc::triangles(
        &[[-0.5, 1.2, 0.0], [0.5, 1.2, 0.0], [0.0, 1.2 + 1e-7, 0.0]],
        Some(m),
    );
    let mesh = d.add_mesh("degenerate", vec![junk, patch, sliver]);
    d.add_node(NodeDesc::new("degenerate").mesh(mesh));
    let s = env.load("degenerate", &d)?;
    ensure!(
        !env.warnings.is_empty(),
        "the loader gave no warning about the degenerate triangles"
    );
    let img = env.render(&s, &cam, gi)?;
    Ok(rel_mse(&img, &clean))
}

fn light_inside(env: &mut Env, gi: &GiSettings) -> Result<f64> {
    let (b, cam) = room(RoomLight::Point(2.0));
    let add_box = |b: &mut SceneBuilder| {
        let m = b.add_material(MaterialDesc::lambertian("crate", WHITE));
        let cube = b.add_mesh("crate", vec![unit_cube(Some(m))]);
        b.add_node(
            NodeDesc::new("crate")
                .mesh(cube)
                .translation([0.5, 1.3, -0.5])
                .scale([0.3; 3]),
        );
    };
    let mut without = b.clone();
    add_box(&mut without);
    let s = env.load("room-crate", &without)?;
    let clean = env.render(&s, &cam, gi)?;
    let mut with = without.clone();
    let l = with.add_light(LightDesc::new("inside", LightType::Point, [1.0; 3], 5.0));
    with.add_node(
        NodeDesc::new("inside")
            .light(l)
            .translation([0.5, 1.3, -0.5]),
    );
    let s = env.load("room-crate-light", &with)?;
    let img = env.render(&s, &cam, gi)?;
    Ok(rel_mse(&img, &clean))
}

fn emissive_dynamic(env: &mut Env, gi: &GiSettings) -> Result<f64> {
    let (b, cam) = room(RoomLight::Point(1.0));
    let place = |b: &SceneBuilder, at: [f32; 3]| {
        let mut b = b.clone();
        let m =
            b.add_material(MaterialDesc::lambertian("glow", WHITE).emissive([1.0, 0.6, 0.3], 5.0));
        let cube = b.add_mesh("glow", vec![unit_cube(Some(m))]);
        b.add_node(
            NodeDesc::new("glow")
                .mesh(cube)
                .translation(at)
                .scale([0.2; 3]),
        );
        b
    };
    let (from, to) = ([-0.5, 1.5, 0.3], [0.3, 1.2, 0.0]);
    let s = env.load("glow-from", &place(&b, from))?;
    let (node, _) = node_of(&s, "glow")?;
    let moved = Mat4::from_translation(Vec3::from(to)) * Mat4::from_scale(Vec3::splat(0.2));
    let img = env.render_dynamic(&s, &cam, gi, Mode::Full, vec![node], |r| {
        r.set_node_transform(node, moved);
        Ok(())
    })?;
    let s = env.load("glow-to", &place(&b, to))?;
    let still = env.render(&s, &cam, gi)?;
    Ok(rel_mse(&img, &still))
}

fn room_at(env: &mut Env, gi: &GiSettings, voxels: u32) -> Result<f64> {
    let (b, cam) = room(RoomLight::Point(2.0));
    let s = env.load("room", &b)?;
    let gi = GiSettings {
        voxels,
        ..gi.clone()
    };
    env.error_vs_reference(&s, &cam, &gi)
}
