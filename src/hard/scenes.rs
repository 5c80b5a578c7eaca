//! The hard cases' scenes, generated with the glTF builder so that they go through the loader
//! like any user's file.

use crate::scene::builder::*;
use crate::scene::Camera;
use glam::{DVec3, Mat4, Vec3};

pub const WHITE: [f32; 3] = [0.8, 0.8, 0.8];

/// Camera-to-world for an eye looking at `target` (+Y up, or +Z when looking along Y).
pub fn look_at(eye: Vec3, target: Vec3, yfov_deg: f32, znear: f32) -> Camera {
    let dir = (target - eye).normalize();
    let up = if dir.cross(Vec3::Y).length() < 1e-3 {
        Vec3::NEG_Z
    } else {
        Vec3::Y
    };
    Camera {
        name: None,
        world: Mat4::look_at_rh(eye, target, up).inverse(),
        yfov: yfov_deg.to_radians(),
        znear,
        zfar: znear * 1e5,
        is_default: false,
    }
}

/// The six inward faces of the box `lo`..`hi`.
pub fn inward_box(lo: [f32; 3], hi: [f32; 3], material: usize) -> PrimitiveDesc {
    let mut faces = Vec::new();
    for axis in 0..3 {
        for (side, at) in [(1.0, lo[axis]), (-1.0, hi[axis])] {
            faces.push(slab_face(lo, hi, axis, at, side, material));
        }
    }
    merge(&faces)
}

/// The face of the box `lo`..`hi` that lies in the plane `x[axis] = at`, facing `side` along
/// that axis.
pub fn slab_face(
    lo: [f32; 3],
    hi: [f32; 3],
    axis: usize,
    at: f32,
    side: f32,
    material: usize,
) -> PrimitiveDesc {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let corner = |a: f32, b: f32| {
        let mut p = [0.0; 3];
        p[axis] = at;
        p[u] = a;
        p[v] = b;
        p
    };
    let mut n = [0.0; 3];
    n[axis] = side;
    quad(
        [
            corner(lo[u], lo[v]),
            corner(hi[u], lo[v]),
            corner(hi[u], hi[v]),
            corner(lo[u], hi[v]),
        ],
        n,
        Some(material),
    )
}

/// What lights the lit room of [`two_rooms`].
#[derive(Clone, Copy, Debug)]
pub enum RoomsLight {
    /// A point light of 2 W/sr, 0.3 m above the room's centre.
    Point,
    /// A 0.6 m emissive square of this strength facing the partition from 0.6 m before the
    /// room's far wall; nothing lights the partition but it and the light it bounces.
    Emitter(f32),
}

/// Two closed rooms of 2 m side split along `axis` by a partition of `thickness` (0: two
/// opposite faces in one plane) moved `offset` metres towards the dark room from the middle,
/// the room on the negative side lit by `light`. In the middle the partition's faces lie on a
/// voxel boundary (64^3), each in a voxel of its own side; 2 cm off they share a voxel.
/// Returns the scene and the camera of each room (lit, dark).
pub fn two_rooms(
    axis: usize,
    thickness: f32,
    light: RoomsLight,
    offset: f32,
) -> (SceneBuilder, Camera, Camera) {
    let mut b = SceneBuilder::new();
    let white = b.add_material(MaterialDesc::lambertian("white", WHITE));
    let mut lo = [-1.0, 0.0, -1.0];
    let mut hi = [1.0, 2.0, 1.0];
    let mid = if axis == 1 { 2.0 } else { 0.0 };
    lo[axis] = mid - 2.0;
    hi[axis] = mid + 2.0;
    if axis == 1 {
        lo[1] = 0.0;
        hi[1] = 4.0;
    }
    let t = 0.5 * thickness;
    let walls = merge(&[
        inward_box(lo, hi, white),
        slab_face(lo, hi, axis, mid + offset - t, -1.0, white),
        slab_face(lo, hi, axis, mid + offset + t, 1.0, white),
    ]);
    let mesh = b.add_mesh("rooms", vec![walls]);
    b.add_node(NodeDesc::new("rooms").mesh(mesh));
    let centre = |side: f32| {
        let c = Vec3::from(lo).lerp(Vec3::from(hi), 0.5);
        let mut c = c.to_array();
        c[axis] = mid + side;
        Vec3::from(c)
    };
    let lit = centre(-1.0);
    match light {
        RoomsLight::Point => {
            let light = b.add_light(LightDesc::new("light", LightType::Point, [1.0; 3], 2.0));
            b.add_node(
                NodeDesc::new("light")
                    .light(light)
                    .translation((lit + Vec3::new(0.0, 0.3, 0.0)).to_array()),
            );
        }
        RoomsLight::Emitter(strength) => {
            let glow = b
                .add_material(MaterialDesc::lambertian("glow", WHITE).emissive([1.0; 3], strength));
            // The square's axes: the two other than `axis`, y first where it is one of them.
            let (u, v) = match axis {
                0 => (1, 2),
                1 => (0, 2),
                _ => (1, 0),
            };
            let mut c = lit.to_array();
            c[axis] = mid - 1.4;
            let corner = |du: f32, dv: f32| {
                let mut p = c;
                p[u] += du;
                p[v] += dv;
                p
            };
            let mut n = [0.0; 3];
            n[axis] = 1.0;
            let square = quad(
                [
                    corner(-0.3, -0.3),
                    corner(0.3, -0.3),
                    corner(0.3, 0.3),
                    corner(-0.3, 0.3),
                ],
                n,
                Some(glow),
            );
            let mesh = b.add_mesh("glow", vec![square]);
            b.add_node(NodeDesc::new("glow").mesh(mesh));
        }
    }
    let camera = |c: Vec3| {
        look_at(
            c + Vec3::new(0.0, 0.0, 0.9),
            c + Vec3::new(0.0, -0.3, -1.0),
            70.0,
            0.01,
        )
    };
    (b, camera(lit), camera(centre(1.0)))
}

/// Two 3 x 2.5 x 4 m rooms side by side along x, their floor, ceiling and side walls one
/// surface each, split by a zero-thickness divider at `x = offset` (two faces in one plane)
/// whose edges go 1 cm into the floor, the ceiling and the side walls; a point light of 20 W/sr
/// hangs at mid-height 30 cm from the divider on the negative side. With `door`, the divider
/// has a door 1 m wide and 2 m high (z from 0.5 to 1.5 m). Returns the scene and the camera of
/// each room (lit, dark), each 10 cm from its end wall looking at the divider.
pub fn junction_rooms(offset: f32, door: bool) -> (SceneBuilder, Camera, Camera) {
    let mut b = SceneBuilder::new();
    let white = b.add_material(MaterialDesc::lambertian("white", WHITE));
    let (lo, hi) = ([-3.0, 0.0, -2.0], [3.0, 2.5, 2.0]);
    let (dlo, dhi) = ([lo[0], -0.01, -2.01], [hi[0], 2.51, 2.01]);
    // The divider's pieces: whole, or around the door.
    let pieces = if door {
        vec![
            (dlo, [dhi[0], dhi[1], 0.5]),
            ([dlo[0], dlo[1], 1.5], dhi),
            ([dlo[0], 2.0, 0.5], [dhi[0], dhi[1], 1.5]),
        ]
    } else {
        vec![(dlo, dhi)]
    };
    let mut faces = vec![inward_box(lo, hi, white)];
    for (plo, phi) in pieces {
        faces.push(slab_face(plo, phi, 0, offset, -1.0, white));
        faces.push(slab_face(plo, phi, 0, offset, 1.0, white));
    }
    let walls = merge(&faces);
    let mesh = b.add_mesh("rooms", vec![walls]);
    b.add_node(NodeDesc::new("rooms").mesh(mesh));
    let light = b.add_light(LightDesc::new("light", LightType::Point, [1.0; 3], 20.0));
    b.add_node(
        NodeDesc::new("light")
            .light(light)
            .translation([offset - 0.3, 1.25, 0.0]),
    );
    let camera = |side: f32| {
        look_at(
            Vec3::new(side * 2.9, 1.25, 0.0),
            Vec3::new(offset, 1.25, 0.0),
            70.0,
            0.01,
        )
    };
    (b, camera(-1.0), camera(1.0))
}

/// What lights the test room.
#[derive(Clone, Copy, Debug)]
pub enum RoomLight {
    None,
    /// A point light of this intensity (W/sr) under the ceiling.
    Point(f32),
    /// A point light of this intensity 5 cm under the ceiling, above the short box: its
    /// highlight on the ceiling changes fast with where the light is.
    PointNearCeiling(f32),
    /// A spot under the ceiling pointing down, inner and outer cone angles (radians).
    Spot(f32, f32),
    /// An emissive panel of this strength under the ceiling, `side` metres square.
    Panel {
        strength: f32,
        side: f32,
    },
}

/// A 2 m Cornell-type room, open at the front (+Z), with two boxes, and a camera in front.
pub fn room(light: RoomLight) -> (SceneBuilder, Camera) {
    let mut b = SceneBuilder::new();
    let white = b.add_material(MaterialDesc::lambertian("white", WHITE));
    let red = b.add_material(MaterialDesc::lambertian("red", [0.63, 0.065, 0.05]));
    let green = b.add_material(MaterialDesc::lambertian("green", [0.14, 0.45, 0.091]));
    let (lo, hi) = ([-1.0, 0.0, -1.0], [1.0, 2.0, 1.0]);
    let white_walls = merge(&[
        slab_face(lo, hi, 1, 0.0, 1.0, white),
        slab_face(lo, hi, 1, 2.0, -1.0, white),
        slab_face(lo, hi, 2, -1.0, 1.0, white),
    ]);
    let room = b.add_mesh(
        "room",
        vec![
            white_walls,
            slab_face(lo, hi, 0, -1.0, 1.0, red),
            slab_face(lo, hi, 0, 1.0, -1.0, green),
        ],
    );
    b.add_node(NodeDesc::new("room").mesh(room));
    let cube = b.add_mesh("box", vec![unit_cube(Some(white))]);
    b.add_node(
        NodeDesc::new("tall box")
            .mesh(cube)
            .translation([-0.4, 0.6, -0.3])
            .rotation([0.0, 0.15643446, 0.0, 0.98768834])
            .scale([0.6, 1.2, 0.6]),
    );
    b.add_node(
        NodeDesc::new("short box")
            .mesh(cube)
            .translation([0.4, 0.3, 0.35])
            .rotation([0.0, -0.15643446, 0.0, 0.98768834])
            .scale([0.6, 0.6, 0.6]),
    );
    let top = [0.0, 1.8, 0.0];
    // Pointing down: -Z turned onto -Y (a quarter turn about +X).
    let down = [
        -std::f32::consts::FRAC_1_SQRT_2,
        0.0,
        0.0,
        std::f32::consts::FRAC_1_SQRT_2,
    ];
    match light {
        RoomLight::None => {}
        RoomLight::Point(i) => {
            let l = b.add_light(LightDesc::new("point", LightType::Point, [1.0; 3], i));
            b.add_node(NodeDesc::new("point").light(l).translation(top));
        }
        RoomLight::PointNearCeiling(i) => {
            let l = b.add_light(LightDesc::new("point", LightType::Point, [1.0; 3], i));
            let at = [0.35, 1.95, 0.3];
            b.add_node(NodeDesc::new("point").light(l).translation(at));
        }
        RoomLight::Spot(inner, outer) => {
            let kind = LightType::Spot {
                inner_cone_angle: inner,
                outer_cone_angle: outer,
            };
            let l = b.add_light(LightDesc::new("spot", kind, [1.0; 3], 4.0));
            b.add_node(
                NodeDesc::new("spot")
                    .light(l)
                    .translation(top)
                    .rotation(down),
            );
        }
        RoomLight::Panel { strength, side } => {
            let m = b.add_material(
                MaterialDesc::lambertian("emitter", WHITE).emissive([1.0; 3], strength),
            );
            let (s, y) = (0.5 * side, 1.99);
            let panel = quad(
                [[-s, y, -s], [s, y, -s], [s, y, s], [-s, y, s]],
                [0.0, -1.0, 0.0],
                Some(m),
            );
            let mesh = b.add_mesh("panel", vec![panel]);
            b.add_node(NodeDesc::new("panel").mesh(mesh));
        }
    }
    let camera = look_at(
        Vec3::new(0.0, 1.0, 3.7),
        Vec3::new(0.0, 1.0, 0.0),
        40.0,
        0.05,
    );
    (b, camera)
}

/// A 4 m floor with a box on it, open to the (black) sky, lit by a directional light shining
/// along `direction`.
pub fn yard(direction: Vec3) -> (SceneBuilder, Camera) {
    let mut b = SceneBuilder::new();
    let white = b.add_material(MaterialDesc::lambertian("white", WHITE));
    let floor = quad(
        [
            [-2.0, 0.0, -2.0],
            [2.0, 0.0, -2.0],
            [2.0, 0.0, 2.0],
            [-2.0, 0.0, 2.0],
        ],
        [0.0, 1.0, 0.0],
        Some(white),
    );
    let mesh = b.add_mesh("floor", vec![floor]);
    b.add_node(NodeDesc::new("floor").mesh(mesh));
    let cube = b.add_mesh("box", vec![unit_cube(Some(white))]);
    b.add_node(
        NodeDesc::new("box")
            .mesh(cube)
            .translation([0.0, 0.5, 0.0])
            .rotation([0.0, 0.25881905, 0.0, 0.965_925_8]),
    );
    add_sun(&mut b, direction, 3.0);
    let camera = look_at(
        Vec3::new(2.5, 2.5, 3.5),
        Vec3::new(0.0, 0.3, 0.0),
        50.0,
        0.05,
    );
    (b, camera)
}

/// A directional light of `irradiance` W/m^2 shining along `direction`.
pub fn add_sun(b: &mut SceneBuilder, direction: Vec3, irradiance: f32) {
    let l = b.add_light(LightDesc::new(
        "sun",
        LightType::Directional,
        [1.0; 3],
        irradiance,
    ));
    // The node's -Z axis is the direction the light shines along.
    let q = glam::Quat::from_rotation_arc(Vec3::NEG_Z, direction.normalize());
    b.add_node(NodeDesc::new("sun").light(l).rotation(q.to_array()));
}

/// A closed box of albedo `albedo` whose every face emits radiance `le` (the furnace).
pub fn furnace(albedo: f32, le: f32) -> (SceneBuilder, Camera) {
    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::lambertian("furnace", [albedo; 3]).emissive([1.0; 3], le));
    let walls = inward_box([-1.0, 0.0, -1.0], [1.0, 2.0, 1.0], m);
    let mesh = b.add_mesh("furnace", vec![walls]);
    b.add_node(NodeDesc::new("furnace").mesh(mesh));
    let camera = look_at(
        Vec3::new(0.0, 1.0, 0.5),
        Vec3::new(0.0, 0.8, -1.0),
        70.0,
        0.01,
    );
    (b, camera)
}

/// `b` placed under one root node that scales by `scale` and then translates by `offset`;
/// point and spot intensities scaled by `scale`^2 so that every image stays the same.
pub fn transformed(b: &SceneBuilder, scale: f32, offset: DVec3) -> SceneBuilder {
    let mut out = b.clone();
    out.scale_punctual_intensities(scale * scale);
    out.wrap_roots(
        NodeDesc::new("root")
            .translation(offset.to_array())
            .scale([scale; 3]),
    );
    out
}

/// A camera moved by the same transform as [`transformed`], into the loaded scene's
/// coordinates (relative to its `origin`, in f64 as the loader places the scene).
pub fn transform_camera(c: &Camera, scale: f32, offset: DVec3, origin: DVec3) -> Camera {
    let eye = (c.eye().as_dvec3() * scale as f64 + offset - origin).as_vec3();
    let (_, rot, _) = c.world.to_scale_rotation_translation();
    Camera {
        world: Mat4::from_rotation_translation(rot, eye),
        znear: c.znear * scale,
        zfar: c.zfar * scale,
        ..c.clone()
    }
}

/// The classic Cornell box (0.555 m, its measured albedos) lit only by its 13 x 10.5 cm
/// ceiling quad, two-sided, emissive strength 17, 1 mm below the ceiling; the camera at the
/// open front.
pub fn cornell_quad_light() -> (SceneBuilder, Camera) {
    let mut b = SceneBuilder::new();
    let white = b.add_material(MaterialDesc::lambertian("white", [0.73, 0.73, 0.73]));
    let red = b.add_material(MaterialDesc::lambertian("red", [0.63, 0.065, 0.05]));
    let green = b.add_material(MaterialDesc::lambertian("green", [0.14, 0.45, 0.091]));
    let (lo, hi) = ([0.0, 0.0, 0.0], [0.555, 0.549, 0.559]);
    let white_walls = merge(&[
        slab_face(lo, hi, 1, lo[1], 1.0, white),
        slab_face(lo, hi, 1, hi[1], -1.0, white),
        slab_face(lo, hi, 2, hi[2], -1.0, white),
    ]);
    let room = b.add_mesh(
        "box",
        vec![
            white_walls,
            slab_face(lo, hi, 0, hi[0], -1.0, red),
            slab_face(lo, hi, 0, lo[0], 1.0, green),
        ],
    );
    b.add_node(NodeDesc::new("box").mesh(room));
    let cube = b.add_mesh("block", vec![unit_cube(Some(white))]);
    let turn = |deg: f32| {
        let h = (0.5 * deg).to_radians();
        [0.0, h.sin(), 0.0, h.cos()]
    };
    b.add_node(
        NodeDesc::new("short block")
            .mesh(cube)
            .translation([0.186, 0.0825, 0.169])
            .rotation(turn(-17.0))
            .scale([0.165, 0.165, 0.165]),
    );
    b.add_node(
        NodeDesc::new("tall block")
            .mesh(cube)
            .translation([0.368, 0.165, 0.351])
            .rotation(turn(17.0))
            .scale([0.165, 0.33, 0.165]),
    );
    let mut light = MaterialDesc::lambertian("light", [0.78, 0.78, 0.78]).emissive([1.0; 3], 17.0);
    light.double_sided = true;
    let light = b.add_material(light);
    let (cx, cz, y) = (0.2775, 0.2795, hi[1] - 0.001);
    let (hx, hz) = (0.065, 0.0525);
    let quad_light = quad(
        [
            [cx - hx, y, cz - hz],
            [cx + hx, y, cz - hz],
            [cx + hx, y, cz + hz],
            [cx - hx, y, cz + hz],
        ],
        [0.0, -1.0, 0.0],
        Some(light),
    );
    let mesh = b.add_mesh("light", vec![quad_light]);
    b.add_node(NodeDesc::new("light").mesh(mesh));
    let camera = look_at(
        Vec3::new(0.2775, 0.2745, -0.8),
        Vec3::new(0.2775, 0.2745, 0.0),
        39.3,
        0.01,
    );
    add_camera_node(&mut b, &camera);
    (b, camera)
}

/// Adds `camera` as the file's camera node, so that a user (or the bench) sees what the case
/// sees.
pub fn add_camera_node(b: &mut SceneBuilder, camera: &Camera) {
    let c = b.add_camera(CameraDesc {
        name: Some("camera".into()),
        yfov: camera.yfov,
        znear: camera.znear,
        zfar: Some(camera.zfar),
        aspect_ratio: None,
    });
    let m = camera.world.to_cols_array();
    let mut node = NodeDesc::new("camera").camera(c);
    node.matrix = Some(m);
    b.add_node(node);
}

/// A UV sphere of `rings` x `segments` facets, outward normals.
pub fn uv_sphere(radius: f32, rings: u32, segments: u32, material: usize) -> PrimitiveDesc {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for i in 0..=rings {
        for j in 0..=segments {
            let th = std::f32::consts::PI * i as f32 / rings as f32;
            let ph = std::f32::consts::TAU * j as f32 / segments as f32;
            let n = [th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()];
            normals.push(n);
            positions.push(n.map(|c| c * radius));
        }
    }
    let at = |i: u32, j: u32| i * (segments + 1) + j;
    let mut indices = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            // Counter-clockwise seen from outside.
            if i > 0 {
                indices.extend([a, d, b]);
            }
            if i + 1 < rings {
                indices.extend([d, c, b]);
            }
        }
    }
    PrimitiveDesc {
        positions,
        normals: Some(normals),
        uvs: None,
        indices: Some(indices),
        material: Some(material),
    }
}

/// A closed 4 x 2.5 x 4 m room, pale walls and ceiling (albedo 0.7) and a wooden floor (0.4,
/// 0.28, 0.18): the rooms the area lights' cases are lit in.
fn living_room(b: &mut SceneBuilder) {
    let wall = b.add_material(MaterialDesc::lambertian("wall", [0.7, 0.68, 0.62]));
    let wood = b.add_material(MaterialDesc::lambertian("floor", [0.4, 0.28, 0.18]));
    let (lo, hi) = ([-2.0, 0.0, -2.0], [2.0, 2.5, 2.0]);
    let mut faces = Vec::new();
    for axis in 0..3 {
        for (side, at) in [(1.0, lo[axis]), (-1.0, hi[axis])] {
            if axis != 1 || side < 0.0 {
                faces.push(slab_face(lo, hi, axis, at, side, wall));
            }
        }
    }
    let walls = b.add_mesh(
        "room",
        vec![merge(&faces), slab_face(lo, hi, 1, lo[1], 1.0, wood)],
    );
    b.add_node(NodeDesc::new("room").mesh(walls));
}

/// A 4 x 2.5 x 4 m closed room (pale walls and ceiling, a wooden floor) with a table and a
/// pillar, lit only by four small coloured
/// emitters, 15 to 25 cm across (2 to 4 voxels at 64^3): two spheres and two cubes. The
/// camera stands inside by the front wall.
pub fn emitter_room() -> (SceneBuilder, Camera) {
    let mut b = SceneBuilder::new();
    let white = b.add_material(MaterialDesc::lambertian("white", WHITE));
    living_room(&mut b);
    let blue = b.add_material(MaterialDesc::lambertian("blue", [0.2, 0.3, 0.7]));
    let cube = b.add_mesh("block", vec![unit_cube(Some(white))]);
    b.add_node(
        NodeDesc::new("table")
            .mesh(cube)
            .translation([-0.5, 0.4, -0.6])
            .scale([1.2, 0.8, 0.7]),
    );
    let tall = b.add_mesh("pillar", vec![unit_cube(Some(blue))]);
    b.add_node(
        NodeDesc::new("pillar")
            .mesh(tall)
            .translation([1.0, 0.9, -0.9])
            .scale([0.4, 1.8, 0.4]),
    );
    // Name, colour, size, a sphere (else a cube), where.
    type Emitter = (&'static str, [f32; 3], f32, bool, [f32; 3]);
    let emitters: [Emitter; 4] = [
        (
            "warm sphere",
            [1.0, 0.75, 0.45],
            0.2,
            true,
            [-0.5, 1.3, -0.6],
        ),
        (
            "blue sphere",
            [0.35, 0.55, 1.0],
            0.15,
            true,
            [1.3, 0.3, 0.6],
        ),
        (
            "green cube",
            [0.4, 1.0, 0.45],
            0.25,
            false,
            [-1.5, 2.2, 1.0],
        ),
        ("red cube", [1.0, 0.3, 0.25], 0.18, false, [0.6, 0.09, -1.6]),
    ];
    for (name, colour, size, sphere, at) in emitters {
        let m = b.add_material(MaterialDesc::lambertian(name, [0.8; 3]).emissive(colour, 40.0));
        let prim = if sphere {
            uv_sphere(0.5 * size, 12, 24, m)
        } else {
            unit_cube(Some(m))
        };
        let mesh = b.add_mesh(name, vec![prim]);
        let node = NodeDesc::new(name).mesh(mesh).translation(at);
        let node = if sphere { node } else { node.scale([size; 3]) };
        b.add_node(node);
    }
    let camera = look_at(
        Vec3::new(0.2, 1.5, 1.9),
        Vec3::new(-0.2, 0.8, -1.0),
        60.0,
        0.01,
    );
    add_camera_node(&mut b, &camera);
    (b, camera)
}

/// The room of [`emitter_room`] without its emitters, lit instead by `n` emissive spheres of
/// 12 cm (528 triangles each) on a grid 40 cm under the ceiling: the area lights' cost as their
/// number grows.
pub fn emitter_grid(n: usize) -> (SceneBuilder, Camera) {
    let mut b = SceneBuilder::new();
    living_room(&mut b);
    let side = (n as f32).sqrt().ceil() as usize;
    let m = b.add_material(MaterialDesc::lambertian("lamp", [0.8; 3]).emissive([1.0; 3], 40.0));
    let sphere = b.add_mesh("lamp", vec![uv_sphere(0.06, 12, 24, m)]);
    for k in 0..n {
        let (i, j) = (k % side, k / side);
        let at = |i: usize| -1.6 + 3.2 * (i as f32 + 0.5) / side as f32;
        b.add_node(
            NodeDesc::new(&format!("lamp {k}"))
                .mesh(sphere)
                .translation([at(i), 2.1, at(j)]),
        );
    }
    let camera = look_at(
        Vec3::new(0.0, 1.4, 1.9),
        Vec3::new(0.0, 0.8, -1.0),
        60.0,
        0.01,
    );
    add_camera_node(&mut b, &camera);
    (b, camera)
}

/// A 4 x 2.5 x 4 m room of single quads (albedo 0.6), open on its +X side, seen from outside
/// through the opening; its walls and roof face into the room, or with `outward` the walls
/// face out (a zero-thickness surface's voxel reflects to the side it faces only).
pub fn open_room(outward: bool) -> (SceneBuilder, Camera) {
    let mut b = SceneBuilder::new();
    let grey = b.add_material(MaterialDesc::lambertian("grey", [0.6; 3]));
    let (a, h) = (2.0, 2.5);
    let wall = if outward { -1.0 } else { 1.0 };
    let faces = vec![
        quad(
            [[-a, 0.0, -a], [a, 0.0, -a], [a, 0.0, a], [-a, 0.0, a]],
            [0.0, 1.0, 0.0],
            Some(grey),
        ),
        quad(
            [[-a, h, -a], [a, h, -a], [a, h, a], [-a, h, a]],
            [0.0, -1.0, 0.0],
            Some(grey),
        ),
        quad(
            [[-a, 0.0, -a], [-a, 0.0, a], [-a, h, a], [-a, h, -a]],
            [wall, 0.0, 0.0],
            Some(grey),
        ),
        quad(
            [[-a, 0.0, -a], [a, 0.0, -a], [a, h, -a], [-a, h, -a]],
            [0.0, 0.0, wall],
            Some(grey),
        ),
        quad(
            [[-a, 0.0, a], [a, 0.0, a], [a, h, a], [-a, h, a]],
            [0.0, 0.0, -wall],
            Some(grey),
        ),
    ];
    let mesh = b.add_mesh("room", faces);
    b.add_node(NodeDesc::new("room").mesh(mesh));
    let camera = look_at(
        Vec3::new(4.5, 1.2, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
        60.0,
        0.05,
    );
    (b, camera)
}
