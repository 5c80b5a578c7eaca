//! GPU test support: procedural scenes built directly, and rendering under validation.
#![allow(dead_code)]

use glam::{Mat4, Vec3, Vec4};
use std::path::PathBuf;
use std::sync::Arc;
use voxgi::output::RadianceImage;
use voxgi::render::{RenderSettings, Renderer};
use voxgi::scene::*;
use voxgi::vk::{Context, ContextDesc};

/// A validated context (Khronos layer with synchronization validation).
pub fn context() -> Arc<Context> {
    Context::new(&ContextDesc {
        validate: true,
        ..Default::default()
    })
    .expect("a Vulkan device with the validation layer (lavapipe in CI)")
}

pub fn empty_scene() -> Scene {
    Scene {
        source: PathBuf::from("procedural"),
        vertices: vec![],
        indices: vec![],
        primitives: vec![],
        instances: vec![],
        materials: vec![],
        textures: vec![],
        lights: vec![],
        camera: Camera {
            name: None,
            world: Mat4::IDENTITY,
            yfov: 40f32.to_radians(),
            znear: 0.01,
            zfar: 100.0,
            is_default: false,
        },
        bounds: Aabb::EMPTY,
        origin: glam::DVec3::ZERO,
        nodes: vec![],
        animations: vec![],
        cameras: vec![],
        environment: None,
        warnings: vec![],
    }
}

/// A Lambertian material (metallic 0, specularFactor 0).
pub fn lambert(scene: &mut Scene, albedo: Vec3) -> u32 {
    scene.materials.push(Material {
        base_color: albedo.extend(1.0),
        metallic: 0.0,
        roughness: 1.0,
        specular_factor: 0.0,
        ..Material::default()
    });
    scene.materials.len() as u32 - 1
}

/// A Lambertian emitter of albedo `albedo` emitting `le` (from both faces when `double_sided`).
pub fn emitter(scene: &mut Scene, albedo: Vec3, le: Vec3, double_sided: bool) -> u32 {
    let m = lambert(scene, albedo);
    scene.materials[m as usize].emissive = le;
    scene.materials[m as usize].double_sided = double_sided;
    m
}

/// Adds a quad a, b, c, d (counter-clockwise seen from its front) as one instance.
pub fn quad(scene: &mut Scene, corners: [Vec3; 4], material: u32) {
    let n = (corners[1] - corners[0])
        .cross(corners[2] - corners[0])
        .normalize();
    let t = (corners[1] - corners[0]).normalize();
    let base = scene.vertices.len() as u32;
    let uvs = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let mut bounds = Aabb::EMPTY;
    for (c, uv) in corners.iter().zip(uvs) {
        scene.vertices.push(Vertex {
            position: c.to_array(),
            normal: n.to_array(),
            uv,
            tangent: [t.x, t.y, t.z, 1.0],
        });
        bounds.extend(*c);
    }
    let first = scene.indices.len() as u32;
    scene
        .indices
        .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    add_instance(scene, first, 6, material, bounds);
}

/// Adds indices [first, first + count) as a primitive placed once, at the identity.
fn add_instance(scene: &mut Scene, first: u32, count: u32, material: u32, bounds: Aabb) -> usize {
    scene.primitives.push(Primitive {
        first_index: first,
        index_count: count,
        material,
        bounds,
    });
    scene.instances.push(Instance {
        primitive: scene.primitives.len() as u32 - 1,
        node: scene.instances.len(),
        node_name: None,
        world: Mat4::IDENTITY,
    });
    scene.bounds = scene.bounds.union(&bounds);
    scene.instances.len() - 1
}

/// A white (0.8) floor of half-size `floor_h` under a one-sided square emitter of half-size
/// `lamp_h` and radiance `le`, facing down from height `y`.
pub fn lamp_over_floor(floor_h: f32, lamp_h: f32, y: f32, le: f32) -> Scene {
    let mut s = empty_scene();
    let white = lambert(&mut s, Vec3::splat(0.8));
    floor(&mut s, floor_h, white);
    let lamp = emitter(&mut s, Vec3::ZERO, Vec3::splat(le), false);
    let h = lamp_h;
    quad(
        &mut s,
        [
            Vec3::new(-h, y, h),
            Vec3::new(-h, y, -h),
            Vec3::new(h, y, -h),
            Vec3::new(h, y, h),
        ],
        lamp,
    );
    s
}

/// A horizontal square floor of half-size `h` at y = 0, facing +Y.
pub fn floor(scene: &mut Scene, h: f32, material: u32) {
    quad(
        scene,
        [
            Vec3::new(-h, 0.0, h),
            Vec3::new(h, 0.0, h),
            Vec3::new(h, 0.0, -h),
            Vec3::new(-h, 0.0, -h),
        ],
        material,
    );
}

/// A vertical square wall of half-size `h` in the plane x = 0, facing +X.
pub fn wall_facing_x(scene: &mut Scene, h: f32, material: u32) {
    quad(
        scene,
        [
            Vec3::new(0.0, -h, h),
            Vec3::new(0.0, -h, -h),
            Vec3::new(0.0, h, -h),
            Vec3::new(0.0, h, h),
        ],
        material,
    );
}

/// A Lambertian floor of albedo `albedo` (half-size 2) under a uniform sky `le`, seen from
/// 3 m above at 40 degrees: it gets irradiance pi Le, so its radiance is albedo x Le.
pub fn floor_under_sky(albedo: f32, le: Vec3) -> Scene {
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::splat(albedo));
    floor(&mut s, 2.0, m);
    top_camera(&mut s, 3.0, 40.0);
    s.environment = Some(voxgi::scene::Environment::uniform(le));
    s
}

/// A camera looking straight down at the origin from height `height`.
pub fn top_camera(scene: &mut Scene, height: f32, yfov_deg: f32) {
    scene.camera = Camera {
        name: None,
        world: Mat4::look_at_rh(Vec3::new(0.0, height, 0.0), Vec3::ZERO, Vec3::NEG_Z).inverse(),
        yfov: yfov_deg.to_radians(),
        znear: 0.01,
        zfar: height * 4.0,
        is_default: false,
    };
}

pub fn light(kind: LightKind, radiance: Vec3, position: Vec3, direction: Vec3) -> Light {
    Light {
        name: None,
        kind,
        radiance,
        range: None,
        position,
        direction: direction.normalize(),
    }
}

/// Renders under validation; fails the test on any validation message or leak.
pub fn render(scene: &Scene, settings: RenderSettings) -> RadianceImage {
    render_with(scene, settings, |r| r.render(true).expect("frame"))
}

/// Renders under validation, `frames` driving the renderer (its frames and what changes
/// between them; the last must read back); fails the test on any validation message or leak.
pub fn render_with(
    scene: &Scene,
    settings: RenderSettings,
    frames: impl FnOnce(&mut Renderer),
) -> RadianceImage {
    let ctx = context();
    let stats = ctx.stats.clone();
    let (w, h, pixels) = {
        let mut r = Renderer::new(&ctx, scene, settings).expect("renderer");
        frames(&mut r);
        (r.settings.width, r.settings.height, r.radiance())
    };
    drop(ctx);
    assert_eq!(
        stats.count(),
        0,
        "validation messages:\n{}",
        stats.messages().join("\n")
    );
    let img = RadianceImage {
        width: w,
        height: h,
        pixels,
    };
    // VOXGI_TEST_DUMP=dir keeps each test's image for a look.
    if let Ok(dir) = std::env::var("VOXGI_TEST_DUMP") {
        let name = std::thread::current()
            .name()
            .unwrap_or("test")
            .replace("::", "-");
        let path = std::path::Path::new(&dir).join(format!("{name}.png"));
        voxgi::output::save(&img, &path, 0.0).expect("dump");
    }
    img
}

/// A red floor (x -2 to 2, z -1 to 2) meeting a white wall 2 m high at z = -1, lit by a sun
/// from above and the front, seen from (0, 1.2, 2.2) at 60 degrees: instances 0 (floor) and
/// 1 (wall). Returns the scene and its white material for what is placed in front.
pub fn corner_scene() -> (Scene, u32) {
    let mut s = empty_scene();
    let red = lambert(&mut s, Vec3::new(0.8, 0.1, 0.1));
    let white = lambert(&mut s, Vec3::splat(0.8));
    quad(
        &mut s,
        [
            Vec3::new(-2.0, 0.0, 2.0),
            Vec3::new(2.0, 0.0, 2.0),
            Vec3::new(2.0, 0.0, -1.0),
            Vec3::new(-2.0, 0.0, -1.0),
        ],
        red,
    );
    quad(
        &mut s,
        [
            Vec3::new(-2.0, 0.0, -1.0),
            Vec3::new(2.0, 0.0, -1.0),
            Vec3::new(2.0, 2.0, -1.0),
            Vec3::new(-2.0, 2.0, -1.0),
        ],
        white,
    );
    s.lights.push(light(
        LightKind::Directional,
        Vec3::splat(3.0),
        Vec3::ZERO,
        Vec3::new(-0.3, -1.0, -0.5),
    ));
    look_at(
        &mut s,
        Vec3::new(0.0, 1.2, 2.2),
        Vec3::new(0.0, 0.5, -1.0),
        60.0,
    );
    (s, white)
}

/// Renders `n` frames under validation, then calls `between` once and renders `after` more;
/// returns the last image. Fails on validation messages and non-finite pixels.
pub fn frames(
    scene: &Scene,
    settings: RenderSettings,
    n: u32,
    between: impl FnOnce(&mut Renderer),
    after: u32,
) -> RadianceImage {
    let img = render_with(scene, settings, |r| {
        for _ in 0..n {
            r.render(false).expect("frame");
        }
        between(r);
        for _ in 0..after {
            r.render(false).expect("frame");
        }
        r.render(true).expect("frame");
    });
    assert!(!img.has_non_finite(), "non-finite pixels");
    img
}

/// relMSE of `a` against `b` (same size).
pub fn rel_mse(a: &RadianceImage, b: &RadianceImage) -> f64 {
    voxgi::metrics::try_compare(a, b, 0.0)
        .expect("same size")
        .rel_mse
}

/// World position seen through pixel (x, y) on the plane y = 0, for `top_camera`.
pub fn top_pixel_to_floor(x: u32, y: u32, w: u32, h: u32, height: f32, yfov_deg: f32) -> Vec3 {
    let t = (yfov_deg.to_radians() * 0.5).tan();
    let aspect = w as f32 / h as f32;
    let ndc_x = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
    let ndc_y = 1.0 - (y as f32 + 0.5) / h as f32 * 2.0;
    // Camera looks down -Y with up = -Z: screen right is +X, screen up is -Z.
    Vec3::new(ndc_x * t * aspect * height, 0.0, -ndc_y * t * height)
}

pub fn v4(v: Vec3) -> Vec4 {
    v.extend(1.0)
}

/// Adds triangles (counter-clockwise seen from their fronts) as one primitive placed once;
/// returns the instance index.
pub fn mesh(scene: &mut Scene, triangles: &[[Vec3; 3]], material: u32) -> usize {
    let first = scene.indices.len() as u32;
    let mut bounds = Aabb::EMPTY;
    for p in triangles {
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        let base = scene.vertices.len() as u32;
        for c in p {
            scene.vertices.push(Vertex {
                position: c.to_array(),
                normal: n.to_array(),
                uv: [0.0, 0.0],
                tangent: [1.0, 0.0, 0.0, 1.0],
            });
            bounds.extend(*c);
        }
        scene.indices.extend([base, base + 1, base + 2]);
    }
    let count = scene.indices.len() as u32 - first;
    add_instance(scene, first, count, material, bounds)
}

/// Adds one triangle (with its own primitive and instance) and returns the instance index.
pub fn triangle(scene: &mut Scene, p: [Vec3; 3], uv: [[f32; 2]; 3], material: u32) -> usize {
    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
    let base = scene.vertices.len() as u32;
    let mut bounds = Aabb::EMPTY;
    for (c, uv) in p.iter().zip(uv) {
        scene.vertices.push(Vertex {
            position: c.to_array(),
            normal: n.to_array(),
            uv,
            tangent: [1.0, 0.0, 0.0, 1.0],
        });
        bounds.extend(*c);
    }
    let first = scene.indices.len() as u32;
    scene.indices.extend([base, base + 1, base + 2]);
    add_instance(scene, first, 3, material, bounds)
}

/// Renders `frames` frames under validation and reads the voxels back.
pub fn render_voxels(scene: &Scene, settings: RenderSettings) -> voxgi::gi::VoxelDump {
    let ctx = context();
    let stats = ctx.stats.clone();
    let dump = {
        let mut r = Renderer::new(&ctx, scene, settings).expect("renderer");
        r.render(false).expect("frame");
        r.read_voxels()
            .expect("readback")
            .expect("voxel passes ran")
    };
    drop(ctx);
    assert_eq!(
        stats.count(),
        0,
        "validation messages:\n{}",
        stats.messages().join("\n")
    );
    dump
}

/// 6-connected flood fill through empty voxels from every empty boundary voxel; true where
/// the outside reaches.
pub fn outside_reach(d: &voxgi::gi::VoxelDump) -> Vec<bool> {
    let n = d.resolution as i32;
    let mut seen = vec![false; d.filled.len()];
    let mut stack = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let on_edge = x == 0 || y == 0 || z == 0 || x == n - 1 || y == n - 1 || z == n - 1;
                let i = d.index(x as u32, y as u32, z as u32);
                if on_edge && !d.filled[i] && !seen[i] {
                    seen[i] = true;
                    stack.push((x, y, z));
                }
            }
        }
    }
    while let Some((x, y, z)) = stack.pop() {
        for (dx, dy, dz) in [
            (1, 0, 0),
            (-1, 0, 0),
            (0, 1, 0),
            (0, -1, 0),
            (0, 0, 1),
            (0, 0, -1),
        ] {
            let (a, b, c) = (x + dx, y + dy, z + dz);
            if a < 0 || b < 0 || c < 0 || a >= n || b >= n || c >= n {
                continue;
            }
            let i = d.index(a as u32, b as u32, c as u32);
            if !d.filled[i] && !seen[i] {
                seen[i] = true;
                stack.push((a, b, c));
            }
        }
    }
    seen
}

/// The pixel a world point lands on (row 0 at the top), for the scene camera.
pub fn project(scene: &Scene, w: u32, h: u32, p: Vec3) -> (u32, u32) {
    let c = &scene.camera;
    let proj = Mat4::perspective_rh(c.yfov, w as f32 / h as f32, c.znear, c.zfar);
    let clip = proj * c.view() * p.extend(1.0);
    let ndc = clip.truncate() / clip.w;
    let x = ((ndc.x + 1.0) * 0.5 * w as f32).floor() as u32;
    let y = ((1.0 - ndc.y) * 0.5 * h as f32).floor() as u32;
    (x.min(w - 1), y.min(h - 1))
}

/// A camera at `eye` looking at `target`.
pub fn look_at(scene: &mut Scene, eye: Vec3, target: Vec3, yfov_deg: f32) {
    scene.camera = Camera {
        name: None,
        world: Mat4::look_at_rh(eye, target, Vec3::Y).inverse(),
        yfov: yfov_deg.to_radians(),
        znear: 0.01,
        zfar: 100.0,
        is_default: false,
    };
}
