//! The corpus's classes: each draws a scene's layout, materials, lights, camera and sky from
//! its own random stream (docs/corpus.md says what each covers and why).

use super::draft::Draft;
use super::draw::Draw;
use super::shapes::*;
use crate::scene::builder::MaterialDesc;
use glam::{DVec3, Vec3};
use std::f32::consts::PI;

/// A class of scenes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Class {
    /// Rooms lit through openings (windows, doors, an open side) by a sun and a sky, a sky
    /// alone or a light outside; the camera mostly inside.
    Openings,
    /// Closed rooms lit only by emitters of every size and place.
    Emitters,
    /// Glossy metal and dielectric floors and objects under a point or area light.
    Materials,
    /// Objects standing on floors under point, spot and area lights near and far.
    Objects,
    /// Scenes from 0.5 m to 100 m across, small buildings on large grounds, far from the
    /// origin.
    Scale,
}

impl Class {
    pub const ALL: [Class; 5] = [
        Class::Openings,
        Class::Emitters,
        Class::Materials,
        Class::Objects,
        Class::Scale,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Class::Openings => "openings",
            Class::Emitters => "emitters",
            Class::Materials => "materials",
            Class::Objects => "objects",
            Class::Scale => "scale",
        }
    }

    pub fn from_name(name: &str) -> Option<Class> {
        Class::ALL.into_iter().find(|c| c.name() == name)
    }

    /// Draws one scene of the class.
    pub fn draw(self, d: &mut Draw) -> (Draft, f32, DVec3) {
        let mut draft = Draft::new();
        let (scale, offset) = match self {
            Class::Openings => {
                openings(d, &mut draft, Outside::default());
                (1.0, DVec3::ZERO)
            }
            Class::Emitters => {
                emitters(d, &mut draft);
                (1.0, DVec3::ZERO)
            }
            Class::Materials => {
                materials(d, &mut draft);
                (1.0, DVec3::ZERO)
            }
            Class::Objects => {
                objects(d, &mut draft);
                (1.0, DVec3::ZERO)
            }
            Class::Scale => scale(d, &mut draft),
        };
        (draft, scale, offset)
    }
}

/// A room's size: width (x), height (y), depth (z).
fn room_size(d: &mut Draw, across: (f32, f32), height: (f32, f32)) -> Vec3 {
    Vec3::new(
        d.uniform(across.0, across.1),
        d.uniform(height.0, height.1),
        d.uniform(across.0, across.1),
    )
}

/// The walls' make: single quads facing in or out, or boxes 5 to 40 cm thick.
fn wall_make(d: &mut Draw, draft: &mut Draft, quads_out: bool) -> Walls {
    let walls = d.weighted(&[
        (0.5, Walls::Thick(0.0)),
        (0.3, Walls::Quads { facing_in: true }),
        (
            if quads_out { 0.2 } else { 0.0 },
            Walls::Quads { facing_in: false },
        ),
    ]);
    let walls = match walls {
        Walls::Thick(_) => Walls::Thick(d.uniform(0.05, 0.4)),
        w => w,
    };
    draft.note(match walls {
        Walls::Thick(t) => format!("walls {:.0} cm thick", t * 100.0),
        Walls::Quads { facing_in: true } => "walls of single quads facing in".into(),
        Walls::Quads { facing_in: false } => "walls of single quads facing out".into(),
    });
    walls
}

/// Materials of the six sides: grey walls, one of them coloured now and then, a darker floor.
fn side_materials(d: &mut Draw, draft: &mut Draft, coloured: f64) -> [usize; 6] {
    let wall = d.albedo(0.35, 0.85, 0.05);
    let wall_m = draft.matte("wall", wall);
    let floor = draft.matte("floor", d.albedo(0.15, 0.6, 0.1));
    let ceiling = draft.matte("ceiling", d.albedo(0.6, 0.85, 0.02));
    let mut m = [wall_m, wall_m, floor, ceiling, wall_m, wall_m];
    for side in [0, 1, 4, 5] {
        if d.chance(coloured) {
            let mean = d.uniform(0.3, 0.6);
            let c = d.colour(mean);
            m[side] = draft.matte("coloured wall", c);
        }
    }
    m
}

/// A camera inside `size`'s room near one corner, looking across at the far corner.
fn inside_view(d: &mut Draw, draft: &mut Draft, size: Vec3) {
    let (sx, sz) = (d.pick(&[-1.0, 1.0]), d.pick(&[-1.0, 1.0]));
    let inset = |d: &mut Draw, half: f32| half - d.uniform(0.25, 0.45 * half.min(2.0));
    let eye = Vec3::new(
        sx * inset(d, 0.5 * size.x),
        d.uniform(1.1, 1.7).min(size.y - 0.3),
        sz * inset(d, 0.5 * size.z),
    );
    let target = Vec3::new(
        -sx * 0.5 * size.x * d.uniform(0.4, 1.0),
        d.uniform(0.3, 1.3),
        -sz * 0.5 * size.z * d.uniform(0.4, 1.0),
    );
    let fov = d.uniform(55.0, 80.0);
    draft.camera(eye, target, fov);
}

/// Where things may stand on a room's floor: a point at least `margin` from the walls.
fn floor_spot(d: &mut Draw, size: Vec3, margin: f32) -> Vec3 {
    let m = |half: f32| (half - margin).max(0.0);
    let (hx, hz) = (m(0.5 * size.x), m(0.5 * size.z));
    Vec3::new(d.uniform(-hx, hx), 0.0, d.uniform(-hz, hz))
}

/// A few crates (boxes) on the floor.
fn crates(d: &mut Draw, draft: &mut Draft, size: Vec3, count: u32) {
    let mut parts = Vec::new();
    for _ in 0..count {
        let s = d.uniform(0.3, 1.0);
        let box_size = Vec3::new(s, s * d.uniform(0.5, 1.2), s * d.uniform(0.7, 1.3));
        let m = draft.matte("crate", d.albedo(0.3, 0.8, 0.2));
        parts.push(standing_box(
            floor_spot(d, size, 0.8),
            box_size,
            d.uniform(0.0, PI),
            m,
        ));
    }
    draft.parts("crates", parts);
}

/// What the openings class may be made to do (the scale class asks for a building on a large
/// ground).
struct Outside {
    /// Half the side of the ground plane, as a range (None: drawn).
    ground: Option<(f32, f32)>,
    /// The chance that the camera is inside.
    inside: f64,
}

impl Default for Outside {
    fn default() -> Self {
        Outside {
            ground: None,
            inside: 0.8,
        }
    }
}

/// How light gets into the room.
#[derive(Clone, Copy)]
enum Opening {
    OpenSide,
    Windows,
    Door,
    DoorAndWindows,
}

/// A room lit through openings.
fn openings(d: &mut Draw, draft: &mut Draft, outside: Outside) {
    let size = room_size(d, (2.5, 8.0), (2.4, 3.5));
    draft.note(format!(
        "room {:.1} x {:.1} x {:.1} m",
        size.x, size.y, size.z
    ));
    let walls = wall_make(d, draft, true);
    let ground = match outside.ground {
        Some((lo, hi)) => Some(d.log_uniform(lo, hi)),
        None => d
            .chance(0.7)
            .then(|| d.log_uniform(size.x.max(size.z) * 1.5, 40.0)),
    };
    let mut room = Room {
        size,
        walls,
        open: [false; 6],
        holes: Default::default(),
        materials: side_materials(d, draft, 0.25),
    };
    if let Some(g) = ground {
        // The room stands on the ground, which is its floor.
        room.open[2] = true;
        let m = draft.matte("ground", d.albedo(0.15, 0.45, 0.1));
        draft.parts(
            "ground",
            vec![panel(
                Vec3::new(-g, 0.0, -g),
                Vec3::new(g, 0.0, g),
                1,
                0.0,
                1.0,
                m,
            )],
        );
        draft.note(format!("on a ground {:.0} m across", 2.0 * g));
    }
    let (main_side, lit_sides) = cut_openings(d, draft, &mut room);
    draft.parts("room", room.primitives());
    let n = d.int(0, 3);
    crates(d, draft, size, n);

    light_from_outside(d, draft, &room, main_side, &lit_sides);
    openings_view(d, draft, &room, main_side, outside.inside);
}

/// The openings in the room's walls (and now and then its ceiling): the side most of the light
/// comes through, and every side that has an opening.
fn cut_openings(d: &mut Draw, draft: &mut Draft, room: &mut Room) -> (usize, Vec<usize>) {
    let size = room.size;
    let opening = d.pick(&[
        Opening::OpenSide,
        Opening::Windows,
        Opening::Door,
        Opening::DoorAndWindows,
    ]);
    let main_side = d.pick(&[0usize, 1, 4, 5]);
    let mut lit_sides = vec![main_side];
    match opening {
        Opening::OpenSide => {
            room.open[main_side] = true;
            draft.note("open on one side");
        }
        Opening::Windows => {
            let n = d.int(1, 3);
            room.holes[main_side] = windows(d, room, main_side, n);
            if d.chance(0.4) {
                let other = d.pick(&[0usize, 1, 4, 5]);
                if other != main_side {
                    room.holes[other] = windows(d, room, other, 1);
                    lit_sides.push(other);
                }
            }
            draft.note(format!("{n} window(s)"));
        }
        Opening::Door | Opening::DoorAndWindows => {
            let r = room.side_rect(main_side);
            let w = d.uniform(0.8, 1.6).min(r.u[1] - r.u[0] - 0.4);
            let h = d.uniform(1.9, 2.3).min(size.y - 0.1);
            let at = d.uniform(r.u[0] + 0.2, r.u[1] - 0.2 - w);
            room.holes[main_side].push(Rect {
                u: [at, at + w],
                v: [0.0, h],
            });
            draft.note(format!("a door {w:.1} x {h:.1} m"));
            if matches!(opening, Opening::DoorAndWindows) {
                let other = d.pick(&[0usize, 1, 4, 5]);
                if other != main_side {
                    let n = d.int(1, 2);
                    room.holes[other] = windows(d, room, other, n);
                    lit_sides.push(other);
                    draft.note("and windows");
                }
            }
        }
    }
    if d.chance(0.15) {
        let (w, l) = (d.uniform(0.5, 1.5), d.uniform(0.5, 1.5));
        let c = floor_spot(d, size, 0.5 + w.max(l));
        room.holes[3].push(Rect {
            u: [c.x - 0.5 * w, c.x + 0.5 * w],
            v: [c.z - 0.5 * l, c.z + 0.5 * l],
        });
        draft.note("a skylight");
    }
    (main_side, lit_sides)
}

/// A sun and a sky, a sky alone, or a lamp outside the room's main opening.
fn light_from_outside(
    d: &mut Draw,
    draft: &mut Draft,
    room: &Room,
    main_side: usize,
    lit_sides: &[usize],
) {
    let light = d.weighted(&[(0.45, 0), (0.35, 1), (0.2, 2)]);
    match light {
        0 | 1 => {
            let tint = if d.chance(0.5) {
                [0.75, 0.9, 1.25]
            } else {
                [1.0; 3]
            };
            let sky = d.log_uniform(0.3, 1.5);
            draft.sky = Some(tint.map(|t| t * sky));
            if light == 0 {
                let el = d.uniform(15.0, 65.0).to_radians();
                // Mostly towards an opening, so that the sun comes in.
                let az = if d.chance(0.7) {
                    let (axis, _, into) = room.plane(d.pick(lit_sides));
                    let towards = if axis == 0 {
                        -into * Vec3::X
                    } else {
                        -into * Vec3::Z
                    };
                    towards.x.atan2(towards.z) + d.uniform(-0.6, 0.6)
                } else {
                    d.uniform(0.0, 2.0 * PI)
                };
                let e = d.uniform(2.0, 8.0);
                draft.sun(el, az, [1.0, 0.95, 0.85], e);
                draft.note(format!(
                    "sun {:.0} deg high, {e:.1} W/m^2, and a sky of {sky:.2}",
                    el.to_degrees()
                ));
            } else {
                draft.note(format!("a sky of {sky:.2} only"));
            }
        }
        _ => {
            let (axis, at, into) = room.plane(main_side);
            let mut p = Vec3::new(0.0, d.uniform(1.0, 3.0), 0.0);
            p[axis] = at - into * d.uniform(0.8, 3.0);
            let i = d.log_uniform(10.0, 150.0);
            draft.point("lamp outside", p, [1.0, 0.9, 0.8], i);
            draft.note(format!("a {i:.0} W/sr light outside"));
        }
    }
}

/// The camera: inside (a share `inside` of the scenes) or outside the main opening.
fn openings_view(d: &mut Draw, draft: &mut Draft, room: &Room, main_side: usize, inside: f64) {
    let size = room.size;
    if d.chance(inside) {
        inside_view(d, draft, size);
        draft.note("seen from inside");
    } else {
        let (axis, at, into) = room.plane(main_side);
        let mut eye = Vec3::new(0.0, d.uniform(1.2, 2.0), 0.0);
        eye[axis] = at - into * d.uniform(1.5, 4.0);
        let other = 2 - axis;
        eye[other] = d.uniform(-0.3, 0.3) * size[other];
        let target = Vec3::new(0.0, d.uniform(0.6, 1.4), 0.0);
        draft.camera(eye, target, d.uniform(50.0, 70.0));
        draft.note("seen from outside");
    }
}

/// `n` windows side by side in a wall, each in a slot of its own.
fn windows(d: &mut Draw, room: &Room, side: usize, n: u32) -> Vec<Rect> {
    let r = room.side_rect(side);
    let slot = (r.u[1] - r.u[0]) / n as f32;
    let h = room.size.y;
    (0..n)
        .map(|i| {
            let w = d.uniform(0.5, 2.5).min(slot - 0.3);
            let wh = d.uniform(0.6, 1.6).min(h - 0.8);
            let sill = d.uniform(0.5, 1.2).min(h - 0.2 - wh);
            let at = r.u[0] + slot * i as f32 + d.uniform(0.15, slot - 0.15 - w);
            Rect {
                u: [at, at + w],
                v: [sill, sill + wh],
            }
        })
        .collect()
}

/// A closed room lit only by emitters.
fn emitters(d: &mut Draw, draft: &mut Draft) {
    let size = room_size(d, (3.0, 7.0), (2.4, 3.2));
    draft.note(format!(
        "closed room {:.1} x {:.1} x {:.1} m",
        size.x, size.y, size.z
    ));
    let walls = wall_make(d, draft, false);
    let room = Room {
        size,
        walls,
        open: [false; 6],
        holes: Default::default(),
        materials: side_materials(d, draft, 0.4),
    };
    draft.parts("room", room.primitives());
    let voxel = size.max_element() / 64.0;
    let n = d.int(1, 4);
    for i in 0..n {
        let kind = d.int(0, 6);
        let size_max = 0.25 * size.x.min(size.z);
        // Down to a tenth of a voxel where the emitter floats or hangs; an emitter that
        // touches a surface is at least 8 cm, since a smaller one lights a spot beside it so
        // small and bright that the path tracer's reference does not converge in hours
        // (docs/corpus.md).
        let touches = matches!(kind, 1..=3 | 5);
        let s = d.log_uniform(if touches { 0.08 } else { 0.1 * voxel }, size_max);
        let power = d.log_uniform(10.0, 150.0);
        let colour = if d.chance(0.6) {
            [1.0, d.uniform(0.8, 1.0), d.uniform(0.6, 0.9)]
        } else {
            d.colour(0.6)
        };
        let name = format!("emitter {i}");
        let spot = floor_spot(d, size, 0.3 + s);
        let support = draft.matte("support", d.albedo(0.3, 0.8, 0.1));
        let mut parts = Vec::new();
        let mut glow = Vec::new();
        let area;
        let what;
        match kind {
            0 => {
                // A ceiling panel facing down.
                let (w, l) = (s.max(0.05), s.max(0.05) * d.uniform(0.5, 2.0));
                let y = size.y - 0.01;
                glow.push(panel(
                    Vec3::new(spot.x - 0.5 * w, y, spot.z - 0.5 * l),
                    Vec3::new(spot.x + 0.5 * w, y, spot.z + 0.5 * l),
                    1,
                    y,
                    -1.0,
                    0,
                ));
                area = w * l;
                what = format!("a ceiling panel {:.0} x {:.0} cm", w * 100.0, l * 100.0);
            }
            1..=3 => {
                // A cube on a pedestal of its footprint, on a table or on the floor.
                let base = match kind {
                    1 => {
                        let h = d.uniform(0.3, 1.1);
                        parts.push(standing_box(spot, Vec3::new(s, h, s), 0.0, support));
                        h
                    }
                    2 => {
                        let top = Vec3::new(
                            (s + 0.2).max(d.uniform(0.6, 1.4)),
                            d.uniform(0.6, 0.9),
                            (s + 0.2).max(d.uniform(0.5, 1.0)),
                        );
                        let (t, h) = table(spot, top, 0.0, support);
                        parts.extend(t);
                        h
                    }
                    _ => 0.0,
                };
                glow.push(standing_box(spot + Vec3::Y * base, Vec3::splat(s), 0.0, 0));
                area = 5.0 * s * s;
                what = format!(
                    "a {:.1} cm cube {}",
                    s * 100.0,
                    ["", "on a pedestal", "on a table", "on the floor"][kind as usize]
                );
            }
            4 | 5 => {
                // A sphere floating, or resting on the floor.
                let r = 0.5 * s;
                let y = if kind == 4 {
                    d.uniform(0.4, size.y - 0.4 - r)
                } else {
                    r
                };
                glow.push(sphere(spot + Vec3::Y * y, r, 0));
                area = 4.0 * PI * r * r;
                what = format!(
                    "a {:.1} cm sphere {}",
                    s * 100.0,
                    if kind == 4 {
                        "floating"
                    } else {
                        "on the floor"
                    }
                );
            }
            _ => {
                // A strip along a wall, 4 cm off it.
                let side = d.pick(&[0usize, 1, 4, 5]);
                let (axis, at, into) = room.plane(side);
                let r = room.side_rect(side);
                let len = d.uniform(0.4, 0.8) * (r.u[1] - r.u[0]);
                let h = s.clamp(0.02, 0.1);
                let y = d.uniform(0.2, size.y - 0.2);
                let mut lo = Vec3::ZERO;
                let mut hi = Vec3::ZERO;
                let along = 2 - axis;
                lo[along] = -0.5 * len;
                hi[along] = 0.5 * len;
                lo[1] = y;
                hi[1] = y + h;
                lo[axis] = at + into * 0.04;
                hi[axis] = at + into * (0.04 + h);
                glow.push(solid_box(lo.min(hi), lo.max(hi), 0));
                area = len * h * 3.0;
                what = format!("a strip {:.1} m x {:.1} cm along a wall", len, h * 100.0);
            }
        }
        let le = power / (PI * area.max(1e-8));
        let m = draft.emitter(&name, colour.map(|c| c * le));
        for g in &mut glow {
            g.material = Some(m);
        }
        parts.extend(glow);
        draft.parts(&name, parts);
        draft.note(format!("{what}, {power:.0} W"));
    }
    inside_view(d, draft, size);
}

/// A material drawn for a glossy surface: metal or dielectric of roughness 0.05 to 0.6.
fn glossy(d: &mut Draw, draft: &mut Draft, name: &str) -> (usize, String) {
    let roughness = d.uniform(0.05, 0.6);
    if d.chance(0.5) {
        let metals = [
            ("silver", [0.95, 0.93, 0.88]),
            ("gold", [1.0, 0.78, 0.34]),
            ("copper", [0.95, 0.64, 0.54]),
            ("steel", [0.56, 0.57, 0.58]),
        ];
        let (metal, colour) = d.pick(&metals);
        let m = draft.material(MaterialDesc {
            name: Some(name.into()),
            base_color: [colour[0], colour[1], colour[2], 1.0],
            metallic: 1.0,
            roughness,
            ..Default::default()
        });
        (m, format!("{metal} of roughness {roughness:.2}"))
    } else {
        let a = d.albedo(0.05, 0.9, 0.3);
        let m = draft.material(MaterialDesc {
            name: Some(name.into()),
            base_color: [a[0], a[1], a[2], 1.0],
            metallic: 0.0,
            roughness,
            ..Default::default()
        });
        (
            m,
            format!(
                "dielectric of albedo {:.2}, roughness {roughness:.2}",
                (a[0] + a[1] + a[2]) / 3.0
            ),
        )
    }
}

/// A glossy floor and objects under a point or area light.
fn materials(d: &mut Draw, draft: &mut Draft) {
    let size = room_size(d, (2.5, 6.0), (2.4, 3.0));
    let open_front = d.chance(0.4);
    let mut room = Room {
        size,
        walls: Walls::Quads { facing_in: true },
        open: [false; 6],
        holes: Default::default(),
        materials: side_materials(d, draft, 0.5),
    };
    let (floor, what) = glossy(d, draft, "floor");
    room.materials[2] = floor;
    draft.note(format!(
        "room {:.1} x {:.1} x {:.1} m{}, floor {what}",
        size.x,
        size.y,
        size.z,
        if open_front { " open in front" } else { "" }
    ));
    if open_front {
        room.open[5] = true;
    }
    draft.parts("room", room.primitives());
    let n = d.int(2, 5);
    let mut parts = Vec::new();
    for _ in 0..n {
        let m = match d.int(0, 2) {
            0 => draft.matte("object", d.albedo(0.05, 0.9, 0.4)),
            _ => glossy(d, draft, "object").0,
        };
        let at = floor_spot(d, size, 0.6);
        if d.chance(0.5) {
            let s = d.uniform(0.2, 0.8);
            parts.push(standing_box(
                at,
                Vec3::new(s, s * d.uniform(0.5, 2.5), s),
                d.uniform(0.0, PI),
                m,
            ));
        } else {
            let r = d.uniform(0.1, 0.45);
            parts.push(sphere(at + Vec3::Y * r, r, m));
        }
    }
    draft.parts("objects", parts);
    draft.note(format!("{n} objects"));
    let light = d.int(0, 2);
    if light != 1 {
        let below = d.log_uniform(0.05, 0.6);
        let i = d.uniform(2.0, 15.0) * (size.y / 2.5).powi(2);
        let at = floor_spot(d, size, 0.5);
        draft.point("lamp", at + Vec3::Y * (size.y - below), [1.0, 0.92, 0.8], i);
        draft.note(format!(
            "a {i:.1} W/sr point light {:.0} cm under the ceiling",
            below * 100.0
        ));
    }
    if light != 0 {
        let s = d.uniform(0.3, 1.2);
        let y = size.y - 0.01;
        let le = d.uniform(20.0, 60.0) / (PI * s * s);
        let m = draft.emitter("panel", [le, le * 0.95, le * 0.85]);
        draft.parts(
            "panel",
            vec![panel(
                Vec3::new(-0.5 * s, y, -0.5 * s),
                Vec3::new(0.5 * s, y, 0.5 * s),
                1,
                y,
                -1.0,
                m,
            )],
        );
        draft.note(format!("a ceiling panel {:.0} cm wide", s * 100.0));
    }
    // Looking down at the floor, so that it reflects the objects.
    let eye = Vec3::new(
        d.uniform(-0.3, 0.3) * size.x,
        d.uniform(1.0, 2.0).min(size.y - 0.3),
        0.5 * size.z - d.uniform(0.2, 0.6),
    );
    let target = Vec3::new(
        d.uniform(-0.2, 0.2) * size.x,
        0.0,
        -d.uniform(0.0, 0.3) * size.z,
    );
    draft.camera(eye, target, d.uniform(45.0, 70.0));
}

/// Objects on a floor under point, spot and area lights from 2 cm to metres from surfaces.
fn objects(d: &mut Draw, draft: &mut Draft) {
    let size = room_size(d, (2.0, 8.0), (2.2, 3.5));
    let walls = wall_make(d, draft, false);
    let cornell = d.chance(0.3);
    let mut room = Room {
        size,
        walls,
        open: [false; 6],
        holes: Default::default(),
        materials: side_materials(d, draft, 0.2),
    };
    if cornell {
        room.materials[0] = draft.matte("red", [0.63, 0.065, 0.05]);
        room.materials[1] = draft.matte("green", [0.14, 0.45, 0.091]);
        room.open[5] = d.chance(0.5);
    }
    draft.note(format!(
        "room {:.1} x {:.1} x {:.1} m{}",
        size.x,
        size.y,
        size.z,
        if cornell { ", red and green walls" } else { "" }
    ));
    draft.parts("room", room.primitives());
    let n = d.int(2, 6);
    let mut parts = Vec::new();
    let mut tops = Vec::new();
    let mut kinds = Vec::new();
    for _ in 0..n {
        let m = draft.matte("object", d.albedo(0.05, 0.9, 0.3));
        let at = floor_spot(d, size, 0.5);
        match d.int(0, 3) {
            0 => {
                let s = d.uniform(0.2, 0.9);
                let h = s * d.uniform(0.5, 3.0);
                parts.push(standing_box(at, Vec3::new(s, h, s), d.uniform(0.0, PI), m));
                tops.push(at + Vec3::Y * h);
                kinds.push("box");
            }
            1 => {
                let r = d.uniform(0.1, 0.5);
                parts.push(sphere(at + Vec3::Y * r, r, m));
                tops.push(at + Vec3::Y * 2.0 * r);
                kinds.push("sphere");
            }
            2 => {
                let (r, h) = (d.uniform(0.01, 0.04), d.uniform(0.5, 2.0).min(size.y - 0.2));
                parts.push(cylinder(at, r, h, m));
                tops.push(at + Vec3::Y * h);
                kinds.push("pole");
            }
            _ => {
                let top = Vec3::new(
                    d.uniform(0.6, 1.6),
                    d.uniform(0.6, 0.9),
                    d.uniform(0.5, 1.0),
                );
                let (t, h) = table(at, top, d.uniform(0.0, PI), m);
                parts.extend(t);
                tops.push(at + Vec3::Y * h);
                kinds.push("table");
            }
        }
    }
    draft.parts("objects", parts);
    draft.note(kinds.join(", "));
    let lights = d.int(1, 2);
    for i in 0..lights {
        let name = format!("light {i}");
        match d.int(0, 2) {
            0 => {
                // Near the ceiling or just above an object.
                let gap = d.log_uniform(0.02, 1.5);
                let p = if d.chance(0.6) {
                    floor_spot(d, size, 0.3) + Vec3::Y * (size.y - gap.min(size.y - 0.3))
                } else {
                    let t = tops[d.int(0, tops.len() as u32 - 1) as usize];
                    t + Vec3::Y * gap.min(size.y - t.y - 0.05).max(0.02)
                };
                let i = d.uniform(1.0, 10.0) * (size.y / 2.5).powi(2);
                draft.point(&name, p, [1.0, 0.92, 0.8], i);
                draft.note(format!(
                    "a {i:.1} W/sr point light {:.0} cm from a surface",
                    gap * 100.0
                ));
            }
            1 => {
                let t = tops[d.int(0, tops.len() as u32 - 1) as usize];
                let p = floor_spot(d, size, 0.3) + Vec3::Y * (size.y - d.uniform(0.05, 0.5));
                let outer = d.uniform(15.0, 50.0).to_radians();
                let inner = outer * d.uniform(0.0, 0.9);
                let i = d.uniform(5.0, 30.0) * (size.y / 2.5).powi(2);
                draft.spot(
                    &name,
                    p,
                    t * Vec3::new(1.0, 0.5, 1.0),
                    [1.0, 0.95, 0.9],
                    i,
                    inner,
                    outer,
                );
                draft.note(format!(
                    "a {i:.1} W/sr spot of {:.0} deg",
                    outer.to_degrees()
                ));
            }
            _ => {
                let s = d.uniform(0.2, 1.2);
                let y = size.y - 0.01;
                let c = floor_spot(d, size, 0.2 + s);
                let le = d.uniform(15.0, 60.0) / (PI * s * s);
                let m = draft.emitter(&name, [le, le * 0.95, le * 0.9]);
                draft.parts(
                    &name,
                    vec![panel(
                        Vec3::new(c.x - 0.5 * s, y, c.z - 0.5 * s),
                        Vec3::new(c.x + 0.5 * s, y, c.z + 0.5 * s),
                        1,
                        y,
                        -1.0,
                        m,
                    )],
                );
                draft.note(format!("an area light {:.0} cm wide", s * 100.0));
            }
        }
    }
    // From above, in the room's corner farthest from the objects, looking at them.
    let centre = tops.iter().fold(Vec3::ZERO, |a, &t| a + t) / tops.len() as f32;
    let corner = Vec3::new(
        -centre.x.signum() * (0.5 * size.x - 0.2),
        0.0,
        -centre.z.signum() * (0.5 * size.z - 0.2),
    );
    let mut eye = (centre * Vec3::new(1.0, 0.0, 1.0)).lerp(corner, d.uniform(0.7, 1.0));
    eye.y = d.uniform(1.2, 2.2).min(size.y - 0.2);
    draft.camera(
        eye,
        centre * Vec3::new(1.0, 0.4, 1.0),
        d.uniform(45.0, 75.0),
    );
}

/// Another class's scene scaled to 0.5 m to 100 m across, or a building on a large ground,
/// now and then far from the origin.
fn scale(d: &mut Draw, draft: &mut Draft) -> (f32, DVec3) {
    let kind = d.int(0, 2);
    let s = match kind {
        0 => {
            objects(d, draft);
            let s = d.log_uniform(0.1, 0.4);
            draft.note(format!("scaled by {s:.2}"));
            s
        }
        1 => {
            openings(
                d,
                draft,
                Outside {
                    ground: Some((10.0, 50.0)),
                    inside: 0.5,
                },
            );
            1.0
        }
        _ => {
            emitters(d, draft);
            let s = d.log_uniform(2.0, 12.0);
            draft.note(format!("scaled by {s:.1}"));
            s
        }
    };
    let offset = if d.chance(0.4) {
        let far = d.log_uniform(1e3, 1e5) as f64;
        let az = d.uniform(0.0, 2.0 * PI) as f64;
        draft.note(format!("{far:.0} m from the origin"));
        DVec3::new(far * az.cos(), 0.0, far * az.sin())
    } else {
        DVec3::ZERO
    };
    (s, offset)
}
