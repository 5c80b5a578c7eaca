//! Emissive surfaces light the scene as area lights (src/render/area_lights.rs): exact form
//! factors of polygons, triangles and discs, the specular lobe against a quadrature of the
//! BRDF, one-sided emitters, soft shadows against the path tracer, small emitters, their
//! absence from the voxels' emission, and their moves.

mod gpu;
use glam::{DVec3, Mat4, Vec3};
use gpu::*;
use voxgi::gi::GiSettings;
use voxgi::render::{Mode, RenderSettings, Renderer};
use voxgi::scene::{Material, Scene};

const SIZE: u32 = 48;
const HEIGHT: f32 = 3.0;
const FOV: f32 = 70.0;

fn settings(area_lights: bool) -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        shadow_resolution: 256,
        mode: Mode::Full,
        gi: GiSettings {
            voxels: 64,
            area_lights,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// The floor's radiance summed over the pixels within 60 degrees of the emitter at height `y`
/// (leaving out those under its edge), against the exact sum for radiant intensity
/// `intensity(dir)` towards the floor; their ratio.
fn floor_ratio(img: &voxgi::output::RadianceImage, y: f32, intensity: impl Fn(Vec3) -> f32) -> f64 {
    let (mut got, mut want) = (0.0f64, 0.0f64);
    for py in 0..SIZE {
        for px in 0..SIZE {
            let p = top_pixel_to_floor(px, py, SIZE, SIZE, HEIGHT, FOV);
            let d = Vec3::new(0.0, y, 0.0) - p;
            let cos = d.y / d.length();
            if cos < 0.5 || d.x.hypot(d.z) < 0.1 {
                continue;
            }
            let e = intensity(-d.normalize()) * cos / d.length_squared();
            want += (0.8 / std::f32::consts::PI * e) as f64;
            got += img.at(px, py)[0] as f64;
        }
    }
    got / want
}

/// One frame under validation: the image and the voxels.
fn render_with_voxels(
    scene: &Scene,
    set: RenderSettings,
) -> (voxgi::output::RadianceImage, voxgi::gi::VoxelDump) {
    let ctx = context();
    let stats = ctx.stats.clone();
    let (w, h) = (set.width, set.height);
    let (pixels, dump) = {
        let mut r = Renderer::new(&ctx, scene, set).expect("renderer");
        r.render(true).expect("frame");
        let dump = r.read_voxels().expect("readback").expect("voxels");
        (r.radiance(), dump)
    };
    drop(ctx);
    assert_eq!(stats.count(), 0, "{}", stats.messages().join("\n"));
    let img = voxgi::output::RadianceImage {
        width: w,
        height: h,
        pixels,
    };
    assert!(
        img.pixels.iter().flatten().all(|v| v.is_finite()),
        "NaN/Inf in the image"
    );
    (img, dump)
}

#[test]
fn a_small_emitter_lights_the_floor_as_a_point_light_and_leaves_the_voxels() {
    // A 2 cm emitter (Le = 1e4) 1 m over a white floor, a third of a voxel at 64^3: exactly
    // Le A cos^2 / r^2 on the floor (the floor sees nothing else), where the voxels' path is
    // off by up to 30% (gi.rs, a_small_emitter_in_the_voxels_sends_the_floor_its_own_light).
    let (half, y, le) = (0.01, 1.0, 1e4);
    let mut s = lamp_over_floor(2.0, half, y, le);
    top_camera(&mut s, HEIGHT, FOV);
    let area = (2.0 * half) * (2.0 * half);
    let cosine = |dir: Vec3| le * area * (-dir.y).max(0.0);

    let (img, voxels) = render_with_voxels(&s, settings(true));
    let ratio = floor_ratio(&img, y, cosine);
    // Measured: 1.014 (as voxels: 1.20).
    assert!(
        (ratio - 1.0).abs() < 0.03,
        "the floor gets {ratio} times the emitter's light"
    );
    let held: f32 = voxels.emission.iter().map(|e| e.max_element()).sum();
    assert_eq!(held, 0.0, "the emitter's emission stayed in the voxels");

    // Without: the voxels hold its emission, and the same frame is further off.
    let (img, voxels) = render_with_voxels(&s, settings(false));
    let held: f32 = voxels.emission.iter().map(|e| e.max_element()).sum();
    assert!(held > 0.0, "no emission in the voxels");
    let off = floor_ratio(&img, y, cosine);
    assert!(
        (off - 1.0).abs() > (ratio - 1.0).abs(),
        "as voxels {off}, as a light {ratio}"
    );
}

#[test]
fn a_small_emitter_casts_shadows() {
    // A black 40 cm board half way down, off to +x: the floor in its shadow gets none of the
    // emitter's light (nothing else there reflects), the floor as far off to -x all of it.
    let (half, y, le) = (0.01, 1.0, 1e4);
    let mut s = lamp_over_floor(2.0, half, y, le);
    top_camera(&mut s, HEIGHT, FOV);
    let black = lambert(&mut s, Vec3::ZERO);
    let (cx, b) = (0.6, 0.2);
    // Facing up and down (two quads).
    for (z0, z1) in [(b, -b), (-b, b)] {
        quad(
            &mut s,
            [
                Vec3::new(cx - b, 0.5, z0),
                Vec3::new(cx + b, 0.5, z0),
                Vec3::new(cx + b, 0.5, z1),
                Vec3::new(cx - b, 0.5, z1),
            ],
            black,
        );
    }
    let img = render(&s, settings(true));
    // The shadow spans x 0.8..1.6, |z| < 0.4; the camera sees it past x = 0.96.
    let mean = |inside: &dyn Fn(Vec3) -> bool| {
        let (mut sum, mut n) = (0.0f32, 0);
        for py in 0..SIZE {
            for px in 0..SIZE {
                if inside(top_pixel_to_floor(px, py, SIZE, SIZE, HEIGHT, FOV)) {
                    sum += img.at(px, py)[0];
                    n += 1;
                }
            }
        }
        assert!(n > 4, "only {n} pixels");
        sum / n as f32
    };
    let shadowed = mean(&|p: Vec3| (1.1..1.5).contains(&p.x) && p.z.abs() < 0.3);
    let lit = mean(&|p: Vec3| (-1.5..-1.1).contains(&p.x) && p.z.abs() < 0.3);
    let exact_lit = {
        let d = Vec3::new(0.0, y, 0.0) - Vec3::new(-1.3, 0.0, 0.0);
        let cos = d.y / d.length();
        0.8 / std::f32::consts::PI * le * 4.0 * half * half * cos * cos / d.length_squared()
    };
    assert!(
        (lit / exact_lit - 1.0).abs() < 0.1,
        "lit floor {lit}, exact about {exact_lit}"
    );
    // Measured: 0.014 of it, what the cones gather from the floor's lit coarse texels.
    assert!(
        shadowed < 0.03 * lit,
        "in the board's shadow {shadowed}, lit floor {lit}"
    );
}

/// An emissive cube of side `side` centred at `c`, its faces facing out.
fn emissive_cube(s: &mut Scene, c: Vec3, side: f32, le: f32) {
    let m = emitter(s, Vec3::ZERO, Vec3::splat(le), false);
    let h = 0.5 * side;
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::AXES[axis] * sign;
            let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
            let (u, v) = if sign > 0.0 { (u, v) } else { (v, u) };
            let f = c + n * h;
            quad(
                s,
                [
                    f - h * u - h * v,
                    f + h * u - h * v,
                    f + h * u + h * v,
                    f - h * u + h * v,
                ],
                m,
            );
        }
    }
    // One primitive: the six quads' instances merged into the first.
    let faces = s.instances.len() - 6;
    let first = s.primitives[s.instances[faces].primitive as usize].first_index;
    let prim = s.instances[faces].primitive as usize;
    s.primitives[prim].index_count = 36;
    s.primitives[prim].bounds = voxgi::scene::Aabb {
        min: c - Vec3::splat(h),
        max: c + Vec3::splat(h),
    };
    s.instances.truncate(faces + 1);
    s.primitives.truncate(prim + 1);
    assert_eq!(s.primitives[prim].first_index, first);
}

#[test]
fn a_closed_small_emitter_is_not_shadowed_by_its_own_faces() {
    // A 2 cm emissive cube 1 m over the floor: the light at its centre is inside it, yet its
    // faces do not hide it (they are left out of its own shadow views). The cube radiates
    // Le s^2 (|x| + |y| + |z|) towards a direction; the light spreads that evenly
    // (1.5 Le s^2, the mean); over the floor within 60 degrees the two agree (measured: 0.99).
    let (side, y, le) = (0.02, 1.0, 1e4);
    let mut s = empty_scene();
    let white = lambert(&mut s, Vec3::splat(0.8));
    floor(&mut s, 2.0, white);
    emissive_cube(&mut s, Vec3::new(0.0, y, 0.0), side, le);
    top_camera(&mut s, HEIGHT, FOV);
    let img = render(&s, settings(true));
    let ratio = floor_ratio(&img, y, |d: Vec3| {
        le * side * side * (d.x.abs() + d.y.abs() + d.z.abs())
    });
    assert!(
        (ratio - 1.0).abs() < 0.05,
        "the floor gets {ratio} times the cube's light"
    );
}

#[test]
fn a_moving_small_emitter_lights_where_it_ends() {
    // The emitter is a dynamic node moved 1 m along x: the frame after the move matches a
    // scene built with it there (its light, shadow views and the voxels' light follow it).
    let (half, y, le) = (0.01, 1.0, 1e4);
    let build = |x: f32| {
        let mut s = lamp_over_floor(2.0, half, y, le);
        top_camera(&mut s, HEIGHT, FOV);
        // A wall for the moving light to cast a shadow on and bounce from.
        let white = lambert(&mut s, Vec3::splat(0.8));
        quad(
            &mut s,
            [
                Vec3::new(0.0, 0.0, -0.5),
                Vec3::new(0.0, 0.0, 0.5),
                Vec3::new(0.0, 0.6, 0.5),
                Vec3::new(0.0, 0.6, -0.5),
            ],
            white,
        );
        s.instances[1].world = Mat4::from_translation(Vec3::new(x, 0.0, 0.0));
        s
    };
    let (start, end) = (build(-0.5), build(0.5));
    let lamp_node = start.instances[1].node;
    let mut set = settings(true);
    set.dynamic_nodes = vec![lamp_node];
    set.timings = true;
    let ctx = context();
    let stats = ctx.stats.clone();
    let (before, after) = {
        let mut r = Renderer::new(&ctx, &start, set.clone()).expect("renderer");
        r.render(true).expect("frame");
        let before = r.radiance();
        r.set_node_transform(lamp_node, end.instances[1].world);
        r.render(true).expect("frame");
        let after = r.radiance();
        // Set where it is: nothing to draw or light again.
        r.set_node_transform(lamp_node, end.instances[1].world);
        r.render(false).expect("frame");
        let runs = |pass: &str| {
            let timer = r.timer.as_ref().expect("lavapipe has timestamps");
            let found = timer.samples.iter().find(|(name, _)| name == pass);
            found.map_or(0, |(_, v)| v.len())
        };
        assert_eq!(
            [runs("shadows"), runs("inject")],
            [2, 2],
            "shadow and inject passes over the first frame, the move and a frame set in place"
        );
        (before, after)
    };
    drop(ctx);
    assert_eq!(stats.count(), 0, "{}", stats.messages().join("\n"));
    let image = |pixels| voxgi::output::RadianceImage {
        width: SIZE,
        height: SIZE,
        pixels,
    };
    let want = render(&end, set);
    let moved = voxgi::metrics::compare(&image(after), &want).rel_mse;
    let stayed = voxgi::metrics::compare(&image(before), &want).rel_mse;
    assert!(
        moved < 1e-3,
        "relMSE {moved} against the emitter built there"
    );
    assert!(
        stayed > 0.1,
        "the move changed little: relMSE {stayed} before it"
    );
}

// --- Closed forms -------------------------------------------------------------------------

const FF_SIZE: u32 = 64;

fn direct_settings() -> RenderSettings {
    RenderSettings {
        width: FF_SIZE,
        height: FF_SIZE,
        shadow_resolution: 512,
        mode: Mode::Direct,
        ..Default::default()
    }
}

/// Lambert's form factor, in f64, from a point of the floor (normal +Y) to a polygon
/// (counter-clockwise seen from its front) clipped to the floor's upper side; 0 behind it.
fn exact_form_factor(p: DVec3, poly: &[DVec3]) -> f64 {
    let n = poly.len();
    let mut normal = DVec3::ZERO;
    for i in 0..n {
        normal += (poly[i] - poly[0]).cross(poly[(i + 1) % n] - poly[0]);
    }
    if normal.dot(p - poly[0]) <= 0.0 {
        return 0.0;
    }
    // Sutherland-Hodgman against y >= 0 (relative to p).
    let rel: Vec<DVec3> = poly.iter().map(|v| *v - p).collect();
    let mut clipped = Vec::new();
    for i in 0..n {
        let (a, b) = (rel[i], rel[(i + 1) % n]);
        if a.y >= 0.0 {
            clipped.push(a);
        }
        if (a.y >= 0.0) != (b.y >= 0.0) {
            clipped.push(a + (b - a) * (a.y / (a.y - b.y)));
        }
    }
    let mut sum = 0.0;
    for i in 0..clipped.len() {
        let (a, b) = (clipped[i], clipped[(i + 1) % clipped.len()]);
        if a.length() == 0.0 || b.length() == 0.0 {
            continue;
        }
        let (a, b) = (a.normalize(), b.normalize());
        let c = a.cross(b);
        if c.length() > 0.0 {
            sum += a.dot(b).clamp(-1.0, 1.0).acos() * c.normalize().y;
        }
    }
    // A front face turns clockwise about the normal seen from p.
    -sum / (2.0 * std::f64::consts::PI)
}

/// The form factor from a floor point at horizontal distance `a` from the axis of a disc of
/// radius `r` facing it from height `h` (the disc of the same solid angle, parallel planes).
fn disc_form_factor(h: f64, a: f64, r: f64) -> f64 {
    let s = h * h + a * a + r * r;
    0.5 * (1.0 - (h * h + a * a - r * r) / (s * s - 4.0 * a * a * r * r).sqrt())
}

/// Whether the ray from `eye` to `p` meets a triangle before p (Moller-Trumbore, f64).
fn ray_hits(eye: DVec3, p: DVec3, tris: &[[DVec3; 3]]) -> bool {
    let d = p - eye;
    tris.iter().any(|t| {
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let q = d.cross(e2);
        let det = e1.dot(q);
        if det.abs() < 1e-12 {
            return false;
        }
        let s = (eye - t[0]) / det;
        let u = s.dot(q);
        let r = s.cross(e1);
        let v = d.dot(r);
        let t_hit = e2.dot(r);
        u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t_hit > 0.0 && t_hit < 1.0
    })
}

/// Renders a one-sided emitter of radiance `le` made of `tris` over the white (0.8) floor,
/// seen from above, and compares each floor pixel the emitter does not hide with
/// 0.8 Le F (`exact`); returns the worst relative error, where the exact value is over 1% of
/// its maximum (elsewhere the error relative to that maximum), and how many pixels are lit.
fn form_factor_error(tris: &[[Vec3; 3]], exact: &dyn Fn(DVec3) -> f64) -> (f64, usize, f64) {
    form_factor_error_sided(tris, exact, false)
}

/// [`form_factor_error`] for an emitter that is two-sided or not.
fn form_factor_error_sided(
    tris: &[[Vec3; 3]],
    exact: &dyn Fn(DVec3) -> f64,
    two_sided: bool,
) -> (f64, usize, f64) {
    let le = 10.0f32;
    let mut s = empty_scene();
    let white = lambert(&mut s, Vec3::splat(0.8));
    floor(&mut s, 3.0, white);
    let m = emitter(&mut s, Vec3::ZERO, Vec3::splat(le), two_sided);
    mesh(&mut s, tris, m);
    top_camera(&mut s, HEIGHT, FOV);
    let img = render(&s, direct_settings());
    let eye = DVec3::new(0.0, HEIGHT as f64, 0.0);
    let dtris: Vec<[DVec3; 3]> = tris.iter().map(|t| t.map(|v| v.as_dvec3())).collect();
    let mut want = vec![None; (FF_SIZE * FF_SIZE) as usize];
    for py in 0..FF_SIZE {
        for px in 0..FF_SIZE {
            // Pixels whose footprint the emitter covers in part are left out.
            let hidden = [
                (0.0, 0.0),
                (-0.5, -0.5),
                (0.5, -0.5),
                (-0.5, 0.5),
                (0.5, 0.5),
            ]
            .iter()
            .any(|(dx, dy)| {
                let p = top_pixel_to_floor(px, py, FF_SIZE, FF_SIZE, HEIGHT, FOV);
                let t = (FOV.to_radians() * 0.5).tan() * HEIGHT / FF_SIZE as f32 * 2.0;
                let p = p + Vec3::new(*dx * t, 0.0, *dy * t);
                ray_hits(eye, p.as_dvec3(), &dtris)
            });
            if !hidden {
                let p = top_pixel_to_floor(px, py, FF_SIZE, FF_SIZE, HEIGHT, FOV).as_dvec3();
                want[(py * FF_SIZE + px) as usize] = Some(0.8 * le as f64 * exact(p));
            }
        }
    }
    let max = want.iter().flatten().fold(0.0f64, |m, &w| m.max(w));
    assert!(max > 0.0, "the exact image is black");
    let (mut worst, mut lit, mut dark_worst) = (0.0f64, 0, 0.0f64);
    for (i, w) in want.iter().enumerate() {
        let Some(w) = *w else { continue };
        let got = img.pixels[i][0] as f64;
        if w > 0.01 * max {
            worst = worst.max((got - w).abs() / w);
            lit += 1;
        } else {
            dark_worst = dark_worst.max((got - w).abs() / max);
        }
    }
    (worst, lit, dark_worst)
}

/// The emitter `tris` lights over a thousand floor pixels, each within 1% of `exact` (dark
/// ones within 0.1% of the brightest).
fn assert_form_factors(
    name: &str,
    tris: &[[Vec3; 3]],
    exact: &dyn Fn(DVec3) -> f64,
    two_sided: bool,
) {
    let (worst, lit, dark) = form_factor_error_sided(tris, exact, two_sided);
    eprintln!("{name}: worst {worst:.5} over {lit} pixels, dark {dark:.2e}");
    assert!(lit > 1000, "{name}: only {lit} lit pixels");
    assert!(worst < 0.01, "{name}: a pixel off by {worst}");
    assert!(
        dark < 1e-3,
        "{name}: a dark pixel off by {dark} of the brightest"
    );
}

fn quad_tris(c: [Vec3; 4]) -> Vec<[Vec3; 3]> {
    vec![[c[0], c[1], c[2]], [c[0], c[2], c[3]]]
}

#[test]
fn a_quad_a_triangle_and_a_disc_give_the_floor_their_exact_form_factors() {
    let y = 0.5;
    // Facing down: counter-clockwise seen from below.
    let quad = [
        Vec3::new(-0.3, y, 0.2),
        Vec3::new(-0.3, y, -0.2),
        Vec3::new(0.3, y, -0.2),
        Vec3::new(0.3, y, 0.2),
    ];
    let tri = [
        Vec3::new(-0.3, y, 0.25),
        Vec3::new(0.1, y, -0.3),
        Vec3::new(0.35, y, 0.2),
    ];
    let (r, sides) = (0.3f32, 64);
    let disc: Vec<[Vec3; 3]> = (0..sides)
        .map(|k| {
            let a = |k: usize| std::f32::consts::TAU * k as f32 / sides as f32;
            let p = |k: usize| Vec3::new(r * a(k).cos(), y, r * a(k).sin());
            [Vec3::new(0.0, y, 0.0), p(k), p(k + 1)]
        })
        .collect();
    let poly = |v: &[Vec3]| -> Vec<DVec3> { v.iter().map(|p| p.as_dvec3()).collect() };
    let (q, t) = (poly(&quad), poly(&tri));
    type Exact = Box<dyn Fn(DVec3) -> f64>;
    let cases: [(&str, Vec<[Vec3; 3]>, Exact); 3] = [
        (
            "quad",
            quad_tris(quad),
            Box::new(move |p| exact_form_factor(p, &q)),
        ),
        (
            "triangle",
            vec![tri],
            Box::new(move |p| exact_form_factor(p, &t)),
        ),
        (
            "disc",
            disc,
            Box::new(move |p: DVec3| disc_form_factor(y as f64, p.x.hypot(p.z), r as f64)),
        ),
    ];
    for (name, tris, exact) in cases {
        // The disc is a 64-gon: 0.16% less area than the disc.
        assert_form_factors(name, &tris, &*exact, false);
    }
}

/// The faces of a cube of side `side` centred at `c` and turned by `turn`, each counter-clockwise
/// seen from outside.
fn cube_faces(c: Vec3, side: f32, turn: glam::Quat) -> Vec<[Vec3; 4]> {
    let h = 0.5 * side;
    let mut faces = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::AXES[axis] * sign;
            let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
            let (u, v) = if sign > 0.0 { (u, v) } else { (v, u) };
            let f = n * h;
            faces.push(
                [
                    f - h * u - h * v,
                    f + h * u - h * v,
                    f + h * u + h * v,
                    f - h * u + h * v,
                ]
                .map(|p| c + turn * p),
            );
        }
    }
    faces
}

#[test]
fn a_box_gives_the_floor_the_sum_of_its_faces_form_factors() {
    // A closed emitter is summed over the outline of the faces a point sees (the edges two
    // seen faces share cancel), chained into loops and clipped to the horizon: the floor must
    // get what the faces give one by one. A turned cube above the floor (no clipping), one
    // dipping 8 cm into it (every loop clipped), and two-sided ones, wound out and in: a
    // closed emitter's faces hide their own backs, so those light the floor from their
    // outsides alone, as the path tracer has it (they took the light twice before, once
    // through the far faces' backs: CornellBox-nvpro's back wall, 0.66 where the faces give
    // 0.315 and the path tracer's direct light 0.321).
    let turn = glam::Quat::from_euler(glam::EulerRot::XYZ, 0.5, 0.7, 0.2);
    let reach = 0.5 * 0.4 * 3f32.sqrt();
    let cases = [
        ("above", Vec3::new(0.1, reach + 0.15, 0.0), false, false),
        ("dipping", Vec3::new(0.1, reach - 0.08, 0.0), false, false),
        ("two-sided", Vec3::new(0.1, reach + 0.15, 0.0), true, false),
        (
            "two-sided, wound in",
            Vec3::new(0.1, reach + 0.15, 0.0),
            true,
            true,
        ),
    ];
    for (name, c, two_sided, wound_in) in cases {
        let faces = cube_faces(c, 0.4, turn);
        let mesh_faces: Vec<[Vec3; 4]> = faces
            .iter()
            .map(|q| {
                let mut q = *q;
                if wound_in {
                    q.reverse();
                }
                q
            })
            .collect();
        let tris: Vec<[Vec3; 3]> = mesh_faces.iter().flat_map(|q| quad_tris(*q)).collect();
        let polys: Vec<Vec<DVec3>> = faces
            .iter()
            .map(|q| q.iter().map(|p| p.as_dvec3()).collect())
            .collect();
        let exact = move |p: DVec3| -> f64 { polys.iter().map(|q| exact_form_factor(p, q)).sum() };
        assert_form_factors(name, &tris, &exact, two_sided);
    }
}

#[test]
fn a_floor_inside_a_closed_emitter_sees_it_all_around() {
    // Inside a box whose faces emit inwards every face is seen from the front, so every edge
    // of its outline cancels: the outline cannot stand for the faces there, and the floor must
    // still get the whole hemisphere's light, 0.8 Le.
    let le = 10.0f32;
    let mut s = empty_scene();
    let white = lambert(&mut s, Vec3::splat(0.8));
    quad(
        &mut s,
        [
            Vec3::new(-0.3, -0.3, 0.3),
            Vec3::new(0.3, -0.3, 0.3),
            Vec3::new(0.3, -0.3, -0.3),
            Vec3::new(-0.3, -0.3, -0.3),
        ],
        white,
    );
    let m = emitter(&mut s, Vec3::ZERO, Vec3::splat(le), false);
    let inward: Vec<[Vec3; 3]> = cube_faces(Vec3::ZERO, 2.0, glam::Quat::IDENTITY)
        .iter()
        .flat_map(|q| {
            let mut q = *q;
            q.reverse();
            quad_tris(q)
        })
        .collect();
    mesh(&mut s, &inward, m);
    look_at(
        &mut s,
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::new(0.0, -0.3, -0.01),
        30.0,
    );
    let img = render(&s, direct_settings());
    let (mut lo, mut hi) = (f32::MAX, 0.0f32);
    for p in &img.pixels {
        lo = lo.min(p[0]);
        hi = hi.max(p[0]);
    }
    eprintln!("floor inside the box: {lo} to {hi}, want {}", 0.8 * le);
    assert!(
        (lo - 0.8 * le).abs() < 0.01 * le && (hi - 0.8 * le).abs() < 0.01 * le,
        "the floor {lo} to {hi} against {}",
        0.8 * le
    );
}

#[test]
fn a_tilted_one_sided_quad_through_the_floor_lights_only_what_it_faces() {
    // A quad leaning 30 degrees from the vertical, facing -X and down, its lower edge 20 cm
    // under the floor: the floor in front sees the part above it (the horizon clips the rest),
    // the floor behind its plane and beside it at grazing angles nothing or little.
    let up = Vec3::new(-0.5, 0.75f32.sqrt(), 0.0);
    let (b, t) = (
        Vec3::new(0.4, -0.2, 0.0),
        Vec3::new(0.4, -0.2, 0.0) + 0.9 * up,
    );
    let z = Vec3::new(0.0, 0.0, 0.4);
    let mut c = [b - z, b + z, t + z, t - z];
    let normal = (c[1] - c[0]).cross(c[2] - c[0]);
    if normal.x > 0.0 {
        c.reverse();
    }
    let q: Vec<DVec3> = c.iter().map(|p| p.as_dvec3()).collect();
    let (worst, lit, dark) = form_factor_error(&quad_tris(c), &|p| exact_form_factor(p, &q));
    eprintln!("tilted: worst {worst:.5} over {lit} pixels, dark {dark:.2e}");
    assert!(lit > 500, "only {lit} lit pixels");
    assert!(worst < 0.01, "a pixel off by {worst}");
    assert!(dark < 1e-3, "a dark pixel off by {dark} of the brightest");
}

#[test]
fn a_one_sided_emitter_lights_nothing_behind_it_and_a_two_sided_one_both_sides() {
    // The same quad facing up, then two-sided: the floor below gets nothing, then its light.
    let y = 0.5;
    let up = [
        Vec3::new(-0.3, y, 0.2),
        Vec3::new(0.3, y, 0.2),
        Vec3::new(0.3, y, -0.2),
        Vec3::new(-0.3, y, -0.2),
    ];
    for two_sided in [false, true] {
        let mut s = empty_scene();
        let white = lambert(&mut s, Vec3::splat(0.8));
        floor(&mut s, 3.0, white);
        let m = emitter(&mut s, Vec3::ZERO, Vec3::splat(10.0), two_sided);
        mesh(&mut s, &quad_tris(up), m);
        top_camera(&mut s, HEIGHT, FOV);
        let img = render(&s, direct_settings());
        // The floor at 1 m from the axis (outside the emitter's shadow from the camera).
        let p = top_pixel_to_floor(8, 32, FF_SIZE, FF_SIZE, HEIGHT, FOV);
        let down: Vec<DVec3> = up.iter().rev().map(|v| v.as_dvec3()).collect();
        let want = 0.8 * 10.0 * exact_form_factor(p.as_dvec3(), &down);
        let got = img.at(8, 32)[0] as f64;
        if two_sided {
            assert!(
                (got / want - 1.0).abs() < 0.01,
                "two-sided: {got}, exact {want}"
            );
        } else {
            // The floor (not the emitter's face the camera sees) is black.
            let eye = DVec3::new(0.0, HEIGHT as f64, 0.0);
            let tris: Vec<[DVec3; 3]> = quad_tris(up)
                .iter()
                .map(|t| t.map(|v| v.as_dvec3()))
                .collect();
            let mut floor_total = 0.0;
            for py in 0..FF_SIZE {
                for px in 0..FF_SIZE {
                    let p = top_pixel_to_floor(px, py, FF_SIZE, FF_SIZE, HEIGHT, FOV);
                    if !ray_hits(eye, p.as_dvec3(), &tris) {
                        floor_total += img.at(px, py)[0];
                    }
                }
            }
            assert_eq!(
                floor_total, 0.0,
                "a one-sided emitter facing away lit the floor"
            );
        }
    }
}

/// A 60 x 40 cm quad light (Le 10) 50 cm over a floor of `material`, off to the side, seen
/// from above: each floor pixel against a quadrature of the path tracer's BRDF
/// (voxgi::reference::brdf, written apart from the shaders) over the light. Returns the mean
/// and the worst relative error over the pixels above 5% of the brightest.
fn specular_error(material: Material) -> (f64, f64) {
    use voxgi::reference::brdf::Brdf;
    let (le, y) = (10.0f32, 0.5f32);
    let corners = [
        Vec3::new(0.5, y, 0.2),
        Vec3::new(0.5, y, -0.2),
        Vec3::new(1.1, y, -0.2),
        Vec3::new(1.1, y, 0.2),
    ];
    let mut s = empty_scene();
    s.materials.push(material.clone());
    floor(&mut s, 3.0, 0);
    let m = emitter(&mut s, Vec3::ZERO, Vec3::splat(le), false);
    mesh(&mut s, &quad_tris(corners), m);
    top_camera(&mut s, HEIGHT, FOV);
    let img = render(&s, direct_settings());
    let brdf = Brdf::new(
        material.base_color.truncate(),
        material.metallic,
        material.roughness,
        material.specular_factor,
        material.specular_color,
    );
    let eye = Vec3::new(0.0, HEIGHT, 0.0);
    let dtris: Vec<[DVec3; 3]> = quad_tris(corners)
        .iter()
        .map(|t| t.map(|v| v.as_dvec3()))
        .collect();
    // Floor frame: z up; x, y along the floor.
    let local = |d: Vec3| Vec3::new(d.x, d.z, d.y);
    let n = 48;
    let (du, dv) = (
        (corners[3] - corners[0]) / n as f32,
        (corners[1] - corners[0]) / n as f32,
    );
    let da = du.length() * dv.length();
    let mut pairs = Vec::new();
    for py in 0..FF_SIZE {
        for px in 0..FF_SIZE {
            let p = top_pixel_to_floor(px, py, FF_SIZE, FF_SIZE, HEIGHT, FOV);
            if ray_hits(eye.as_dvec3(), p.as_dvec3(), &dtris) {
                continue;
            }
            let wo = local((eye - p).normalize());
            let mut sum = Vec3::ZERO;
            for i in 0..n {
                for j in 0..n {
                    let q = corners[0] + du * (i as f32 + 0.5) + dv * (j as f32 + 0.5);
                    let d = q - p;
                    let (d2, wi) = (d.length_squared(), d.normalize());
                    let cos_light = wi.y; // the light faces down
                    if wi.y <= 0.0 {
                        continue;
                    }
                    sum += brdf.eval(wo, local(wi)) * wi.y * cos_light / d2 * da;
                }
            }
            pairs.push((img.at(px, py)[1] as f64, (le * sum.y) as f64));
        }
    }
    let max = pairs.iter().fold(0.0f64, |m, p| m.max(p.1));
    let lit: Vec<f64> = pairs
        .iter()
        .filter(|p| p.1 > 0.05 * max)
        .map(|p| (p.0 - p.1).abs() / p.1)
        .collect();
    assert!(lit.len() > 100, "only {} lit pixels", lit.len());
    let mean = lit.iter().sum::<f64>() / lit.len() as f64;
    (mean, lit.iter().fold(0.0, |m, &e| m.max(e)))
}

#[test]
fn a_rough_metal_and_a_rough_dielectric_reflect_a_quad_light_as_the_brdf_says() {
    let metal = Material {
        base_color: glam::Vec4::new(0.9, 0.8, 0.6, 1.0),
        metallic: 1.0,
        roughness: 0.5,
        ..Material::default()
    };
    let dielectric = Material {
        base_color: glam::Vec4::new(0.5, 0.5, 0.5, 1.0),
        metallic: 0.0,
        roughness: 0.4,
        specular_factor: 1.0,
        specular_color: Vec3::ONE,
        ..Material::default()
    };
    let (metal_mean, metal_worst) = specular_error(metal);
    let (diel_mean, diel_worst) = specular_error(dielectric);
    eprintln!("metal: mean {metal_mean:.4}, worst {metal_worst:.4}");
    eprintln!("dielectric: mean {diel_mean:.4}, worst {diel_worst:.4}");
    // Measured: metal mean 0.0227, worst 0.0439 (the LTC fit: src/render/ltc.rs); the
    // dielectric, mostly its diffuse lobe from above, mean 0.0008, worst 0.0031.
    assert!(
        metal_mean < 0.03 && metal_worst < 0.06,
        "metal: mean {metal_mean}, worst {metal_worst}"
    );
    assert!(
        diel_mean < 0.002 && diel_worst < 0.005,
        "dielectric: mean {diel_mean}, worst {diel_worst}"
    );
}

/// The worst difference of the plate's shadow profile from the path tracer's (see below),
/// with the area light's shadow maps at `area_resolution` texels per side.
fn plate_penumbra_error(area_resolution: u32) -> f32 {
    // A 40 cm quad light (Le 10) 1 m up; a black 30 cm plate 40 cm up, 80 cm off to +x: its
    // shadow on the floor spans x 0.95 to 1.72, penumbrae 27 cm wide (0.4 x 0.4 / 0.6) about
    // an umbra 1.22 to 1.45. Seen from 2 m straight over x = 1.3, the profile across it (three
    // rows through its middle) against the path tracer's direct light.
    let le = 10.0f32;
    let size = 96;
    let mut s = lamp_over_floor(3.0, 0.2, 1.0, le);
    let eye = Vec3::new(1.3, 2.0, 0.0);
    s.camera = voxgi::scene::Camera {
        name: None,
        world: Mat4::look_at_rh(eye, Vec3::new(1.3, 0.0, 0.0), Vec3::NEG_Z).inverse(),
        yfov: 40f32.to_radians(),
        znear: 0.01,
        zfar: 10.0,
        is_default: false,
    };
    let black = lambert(&mut s, Vec3::ZERO);
    let (cx, b, h) = (0.8, 0.15, 0.4);
    for (z0, z1) in [(b, -b), (-b, b)] {
        quad(
            &mut s,
            [
                Vec3::new(cx - b, h, z0),
                Vec3::new(cx + b, h, z0),
                Vec3::new(cx + b, h, z1),
                Vec3::new(cx - b, h, z1),
            ],
            black,
        );
    }
    let mut set = direct_settings();
    set.width = size;
    set.height = size;
    set.area_shadow_resolution = area_resolution;
    let img = render(&s, set);
    let reference = voxgi::reference::render(
        &s,
        &voxgi::reference::ReferenceSettings {
            width: size,
            height: size,
            spp: 1024,
            max_depth: 1,
            ..Default::default()
        },
    );
    let mid = size / 2;
    let profile = |im: &voxgi::output::RadianceImage, x: u32| {
        (mid - 1..=mid + 1).map(|y| im.at(x, y)[0]).sum::<f32>() / 3.0
    };
    let lit = (0..size)
        .map(|x| profile(&reference, x))
        .fold(0.0f32, f32::max);
    let mut worst = 0.0f32;
    for x in 1..size - 1 {
        let (got, want) = (profile(&img, x), profile(&reference, x));
        // The plate's silhouette: the path tracer's pixels average it, ours sample it once.
        let jump = (profile(&img, x - 1) - got)
            .abs()
            .max((profile(&img, x + 1) - got).abs());
        if jump > 0.3 * lit {
            continue;
        }
        worst = worst.max((got - want).abs() / lit);
    }
    worst
}

#[test]
fn a_plate_under_a_quad_light_casts_the_path_tracers_penumbra() {
    // The default area shadow maps (512 texels) and ones four times finer: soft shadows
    // need no finer maps.
    let (coarse, fine) = (plate_penumbra_error(512), plate_penumbra_error(2048));
    eprintln!("penumbra profile off by {coarse} (512 texels), {fine} (2048)");
    // Measured: 0.12 with 512 and with 2048 texels (ours a little brighter in the outer half of
    // the penumbra).
    for (res, worst) in [(512, coarse), (2048, fine)] {
        assert!(
            worst < 0.15,
            "{res} texels: the profile is off by {worst} of the lit floor"
        );
    }
}

#[test]
fn the_area_lights_shadow_resolution_leaves_punctual_shadows_alone() {
    // A pole under a quad light and a point light. The point light's share of the image (with
    // it, less without it) is the same whatever the area light's maps; the area light's own
    // shadow changes with them.
    let mut s = lamp_over_floor(3.0, 0.2, 1.0, 2.0);
    let white = lambert(&mut s, Vec3::splat(0.8));
    quad(
        &mut s,
        [
            Vec3::new(0.3, 0.0, 0.0),
            Vec3::new(0.3, 0.0, 0.1),
            Vec3::new(0.3, 0.6, 0.1),
            Vec3::new(0.3, 0.6, 0.0),
        ],
        white,
    );
    top_camera(&mut s, HEIGHT, FOV);
    let mut lit = s.clone();
    lit.lights.push(light(
        voxgi::scene::LightKind::Point,
        Vec3::splat(5.0),
        Vec3::new(0.4, 2.0, 0.3),
        Vec3::NEG_Y,
    ));
    let at = |scene: &Scene, area_shadow_resolution| {
        render(
            scene,
            RenderSettings {
                area_shadow_resolution,
                ..direct_settings()
            },
        )
    };
    let point_share = |res| {
        let (with, without) = (at(&lit, res), at(&s, res));
        let share: Vec<f32> = with
            .pixels
            .iter()
            .zip(&without.pixels)
            .map(|(a, b)| a[0] - b[0])
            .collect();
        (share, without)
    };
    let ((coarse, area_coarse), (fine, area_fine)) = (point_share(64), point_share(1024));
    let brightest = fine.iter().fold(0.0f32, |m, &v| m.max(v));
    assert!(
        brightest > 0.1,
        "the point light adds nothing ({brightest})"
    );
    let worst = coarse
        .iter()
        .zip(&fine)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(
        worst < 1e-5 * brightest,
        "the point light's share changed with the area maps by {worst} (of {brightest})"
    );
    let area_change = area_coarse
        .pixels
        .iter()
        .zip(&area_fine.pixels)
        .map(|(a, b)| (a[0] - b[0]).abs())
        .fold(0.0f32, f32::max);
    assert!(
        area_change > 0.0,
        "the area light's shadow ignores its maps' resolution"
    );
}

#[test]
fn a_quad_light_that_moves_for_ten_frames_stays_finite_and_ends_where_it_is_built() {
    // A 40 cm quad light on a dynamic node slides and turns over ten frames above a floor with
    // a wall; every frame is finite and free of validation messages, and the last matches a
    // scene built with the light there (its polygons, shadow views and voxel light follow).
    let build = |world: Mat4| {
        let mut s = lamp_over_floor(2.0, 0.2, 1.0, 20.0);
        top_camera(&mut s, HEIGHT, FOV);
        let white = lambert(&mut s, Vec3::splat(0.8));
        quad(
            &mut s,
            [
                Vec3::new(0.6, 0.0, -0.5),
                Vec3::new(0.6, 0.0, 0.5),
                Vec3::new(0.6, 0.6, 0.5),
                Vec3::new(0.6, 0.6, -0.5),
            ],
            white,
        );
        s.instances[1].world = world;
        s
    };
    let at = |k: usize| {
        let t = k as f32 / 9.0;
        Mat4::from_translation(Vec3::new(-0.6 + 0.8 * t, 0.0, 0.3 * t))
            * Mat4::from_rotation_z(0.4 * t)
    };
    let start = build(at(0));
    let node = start.instances[1].node;
    let mut set = settings(true);
    set.dynamic_nodes = vec![node];
    let ctx = context();
    let stats = ctx.stats.clone();
    let last = {
        let mut r = Renderer::new(&ctx, &start, set.clone()).expect("renderer");
        let mut last = Vec::new();
        for k in 0..10 {
            r.set_node_transform(node, at(k));
            r.render(true).expect("frame");
            last = r.radiance();
            assert!(
                last.iter().flatten().all(|v| v.is_finite()),
                "frame {k}: non-finite pixels"
            );
            let bad = r.count_non_finite().expect("readback").expect("voxels");
            assert_eq!(bad.total(), 0, "frame {k}: non-finite voxels {bad:?}");
        }
        last
    };
    drop(ctx);
    assert_eq!(stats.count(), 0, "{}", stats.messages().join("\n"));
    let want = render(&build(at(9)), set);
    let got = voxgi::output::RadianceImage {
        width: SIZE,
        height: SIZE,
        pixels: last,
    };
    let err = voxgi::metrics::compare(&got, &want).rel_mse;
    assert!(
        err < 1e-3,
        "relMSE {err} against the light built where it ends"
    );
}

#[test]
fn a_textured_emitter_lights_as_its_textures_mean() {
    // A 60 cm quad light whose emissive texture is half white, half black (Le 10 where white):
    // the light it casts is its mean, 5, over the whole quad (the G-buffer still shows the
    // halves). The floor gets 0.8 x 5 x F(quad) within 1%; against the true light of the
    // white half alone, the error falls with the distance (printed, docs/area-lights.md).
    let (h, y) = (0.3f32, 0.5f32);
    let mut s = lamp_over_floor(3.0, h, y, 10.0);
    s.textures.push(voxgi::scene::Texture {
        name: "halves".into(),
        width: 2,
        height: 1,
        rgba8: vec![255, 255, 255, 255, 0, 0, 0, 255],
        srgb: false,
        wrap_s: voxgi::scene::Wrap::ClampToEdge,
        wrap_t: voxgi::scene::Wrap::ClampToEdge,
        mag_nearest: true,
        min_nearest: true,
    });
    let lamp = s.instances[1].primitive as usize;
    let m = s.primitives[lamp].material as usize;
    s.materials[m].emissive_tex = Some(voxgi::scene::TexRef {
        texture: 0,
        tex_coord: 0,
    });
    top_camera(&mut s, HEIGHT, FOV);
    let img = render(&s, direct_settings());
    // lamp_over_floor's corners, u from the first to the second: the white half is z > 0.
    let whole: Vec<DVec3> = [(-h, h), (-h, -h), (h, -h), (h, h)]
        .iter()
        .map(|&(x, z)| DVec3::new(x as f64, y as f64, z as f64))
        .collect();
    let white: Vec<DVec3> = [(-h, h), (-h, 0.0), (h, 0.0), (h, h)]
        .iter()
        .map(|&(x, z)| DVec3::new(x as f64, y as f64, z as f64))
        .collect();
    let eye = DVec3::new(0.0, HEIGHT as f64, 0.0);
    let tris: Vec<[DVec3; 3]> = vec![
        [whole[0], whole[1], whole[2]],
        [whole[0], whole[2], whole[3]],
    ];
    let (mut worst_mean, mut near, mut far) = (0.0f64, 0.0f64, 0.0f64);
    for py in 0..FF_SIZE {
        for px in 0..FF_SIZE {
            let p = top_pixel_to_floor(px, py, FF_SIZE, FF_SIZE, HEIGHT, FOV).as_dvec3();
            if ray_hits(eye, p, &tris) {
                continue;
            }
            let got = img.at(px, py)[0] as f64;
            let mean = 0.8 * 5.0 * exact_form_factor(p, &whole);
            let truth = 0.8 * 10.0 * exact_form_factor(p, &white);
            if mean > 1e-3 {
                worst_mean = worst_mean.max((got / mean - 1.0).abs());
            }
            if truth > 1e-3 {
                let off = (got / truth - 1.0).abs();
                let d = p.length() / (2.0 * h as f64);
                if d < 1.0 {
                    near = near.max(off);
                } else if d > 3.0 {
                    far = far.max(off);
                }
            }
        }
    }
    eprintln!(
        "textured emitter: the mean within {worst_mean:.4}; against the true light {near:.3} \
         within one light width of its axis, {far:.3} beyond three"
    );
    assert!(
        worst_mean < 0.01,
        "the floor is {worst_mean} off the mean's light"
    );
    assert!(far < near, "far {far}, near {near}");
}
