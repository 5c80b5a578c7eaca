//! Voxelization: the atomic average (and the paper's wrap), watertightness of a closed mesh,
//! HDR emission, and dynamic geometry that leaves static voxels alone.

mod gpu;
use glam::{Mat4, Quat, Vec3};
use gpu::*;
use voxgi::gi::{GiSettings, VoxelGrid};
use voxgi::render::{Mode, RenderSettings};
use voxgi::scene::{Material, Scene, TexRef, Texture, Wrap};

fn voxel_settings(n: u32, paper: bool, mode: Mode) -> RenderSettings {
    RenderSettings {
        width: 16,
        height: 16,
        shadow_resolution: 64,
        mode,
        gi: if paper {
            GiSettings::paper(n)
        } else {
            GiSettings {
                voxels: n,
                ..Default::default()
            }
        },
        ..Default::default()
    }
}

/// Two tiny anchor triangles that make the scene bounds the unit cube.
fn anchor(s: &mut Scene, m: u32) {
    let e = 0.001;
    triangle(
        s,
        [Vec3::ZERO, Vec3::new(e, 0.0, 0.0), Vec3::new(0.0, e, 0.0)],
        [[0.0; 2]; 3],
        m,
    );
    triangle(
        s,
        [
            Vec3::ONE,
            Vec3::new(1.0 - e, 1.0, 1.0),
            Vec3::new(1.0, 1.0 - e, 1.0),
        ],
        [[0.0; 2]; 3],
        m,
    );
}

/// A Lambertian material whose base colour is a new non-sRGB texture of nearest texels.
fn textured(s: &mut Scene, name: &str, width: u32, height: u32, rgba8: Vec<u8>, wrap: Wrap) -> u32 {
    s.textures.push(Texture {
        name: name.into(),
        width,
        height,
        rgba8,
        srgb: false,
        wrap_s: wrap,
        wrap_t: wrap,
        mag_nearest: true,
        min_nearest: true,
    });
    s.materials.push(Material {
        base_color_tex: Some(TexRef {
            texture: s.textures.len() as u32 - 1,
            tex_coord: 0,
        }),
        metallic: 0.0,
        specular_factor: 0.0,
        ..Material::default()
    });
    s.materials.len() as u32 - 1
}

/// Fragments per target voxel: `counts[k]` triangles inside voxel k, each sampling texel
/// `values[k](i)` of a grey ramp texture. Returns the scene and, per target, its voxel and the
/// exact mean of what was written.
fn stacked_triangles(counts: &[u32], varied: bool, n: u32) -> (Scene, Vec<([u32; 3], f32)>) {
    let mut s = empty_scene();
    // A 256-texel ramp: texel t has value t / 255.
    let ramp: Vec<u8> = (0..256u32)
        .flat_map(|t| [t as u8, t as u8, t as u8, 255])
        .collect();
    let m = textured(&mut s, "ramp", 256, 1, ramp, Wrap::ClampToEdge);
    anchor(&mut s, m);
    let grid = VoxelGrid::fit(
        &voxgi::scene::Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        },
        n,
    );
    let vs = grid.voxel_size();
    let mut targets = Vec::new();
    for (k, &count) in counts.iter().enumerate() {
        // Target voxels on a diagonal-free row, away from the anchors.
        let c = [
            2 + (k as u32 % (n - 4)),
            3 + 2 * (k as u32 / (n - 4)),
            n / 2,
        ];
        let centre = grid.origin + (Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) + 0.5) * vs;
        let mut sum = 0.0;
        for i in 0..count {
            let texel = if varied {
                (i * 37 + k as u32 * 11) % 256
            } else {
                204
            };
            sum += texel as f32 / 255.0;
            let u = (texel as f32 + 0.5) / 256.0;
            // A small triangle in the XY plane around the voxel centre (one fragment each).
            let h = 0.25 * vs;
            triangle(
                &mut s,
                [
                    centre + Vec3::new(-h, -h, 0.0),
                    centre + Vec3::new(h, -h, 0.0),
                    centre + Vec3::new(0.0, h, 0.0),
                ],
                [[u, 0.5]; 3],
                m,
            );
        }
        targets.push((c, sum / count as f32));
    }
    (s, targets)
}

const COUNTS: [u32; 12] = [1, 2, 3, 17, 254, 255, 256, 257, 511, 512, 1000, 2000];

#[test]
fn atomic_average_is_exact_for_up_to_2000_fragments() {
    for varied in [false, true] {
        let (s, targets) = stacked_triangles(&COUNTS, varied, 32);
        let d = render_voxels(&s, voxel_settings(32, false, Mode::VoxelsAlbedo));
        for ((c, mean), &count) in targets.iter().zip(&COUNTS) {
            let i = d.index(c[0], c[1], c[2]);
            assert_eq!(d.count[i], count, "voxel {c:?}: fragment count");
            let got = d.albedo[i];
            // Each fragment rounds to 1/4096; the mean is off by at most half of that.
            for ch in 0..3 {
                assert!(
                    (got[ch] - mean).abs() <= 0.5 / 4096.0 + 1e-6,
                    "{count} {} fragments: mean {mean}, got {got}",
                    if varied { "varied" } else { "equal" }
                );
            }
        }
    }
}

#[test]
fn paper_average_wraps_at_256_fragments() {
    let (s, targets) = stacked_triangles(&COUNTS, false, 32);
    let d = render_voxels(&s, voxel_settings(32, true, Mode::VoxelsAlbedo));
    for ((c, mean), &count) in targets.iter().zip(&COUNTS) {
        let i = d.index(c[0], c[1], c[2]);
        let stored = count % 256;
        // The original keeps the count in 8 bits: 256 fragments read as an empty voxel.
        assert_eq!(d.count[i], stored, "{count} fragments: 8-bit count");
        assert_eq!(d.filled[i], stored != 0, "{count} fragments");
        if stored != 0 {
            // The original's voxels hold gamma-space albedo.
            let mean = mean.powf(1.0 / 2.2);
            assert!(
                (d.albedo[i].x - mean).abs() <= 1.0 / 255.0,
                "{count}: {}",
                d.albedo[i]
            );
        }
    }
}

/// A closed, rotated UV sphere.
fn sphere(s: &mut Scene, centre: Vec3, r: f32, m: u32) {
    let (rings, segments) = (24, 48);
    let rot = Quat::from_euler(glam::EulerRot::XYZ, 0.3, 0.7, 0.2);
    let p = |i: u32, j: u32| {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        let ph = 2.0 * std::f32::consts::PI * j as f32 / segments as f32;
        centre + rot * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * r
    };
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            // At the poles one of the two triangles of a quad collapses.
            if i != rings - 1 {
                triangle(s, [a, c, b], [[0.0; 2]; 3], m);
            }
            if i != 0 {
                triangle(s, [a, d, c], [[0.0; 2]; 3], m);
            }
        }
    }
}

#[test]
fn closed_mesh_voxelizes_watertight() {
    for n in [16u32, 37, 64] {
        let mut s = empty_scene();
        let m = lambert(&mut s, Vec3::splat(0.5));
        anchor(&mut s, m);
        let centre = Vec3::new(0.47, 0.52, 0.5);
        sphere(&mut s, centre, 0.33, m);
        let d = render_voxels(&s, voxel_settings(n, false, Mode::VoxelsAlbedo));
        let reach = outside_reach(&d);
        let grid = VoxelGrid::fit(&s.bounds, n);
        let c = ((centre - grid.origin) / grid.voxel_size()).floor();
        let i = d.index(c.x as u32, c.y as u32, c.z as u32);
        assert!(
            !d.filled[i],
            "{n}^3: the sphere's centre is filled (the shell is too thick)"
        );
        assert!(
            !reach[i],
            "{n}^3: the outside leaks into the sphere (a 6-connected hole)"
        );
    }
}

/// A horizontal square facing up, 0.2 to 0.8 in x and z, at height `y`.
fn square(s: &mut Scene, y: f32, material: u32) {
    quad(
        s,
        [
            Vec3::new(0.2, y, 0.8),
            Vec3::new(0.8, y, 0.8),
            Vec3::new(0.8, y, 0.2),
            Vec3::new(0.2, y, 0.2),
        ],
        material,
    );
}

#[test]
fn hdr_emission_survives_unclamped() {
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::splat(0.5));
    anchor(&mut s, m);
    emitter(&mut s, Vec3::ZERO, Vec3::new(17.0, 4.0, 0.25), false);
    square(&mut s, 0.5, 1);
    // The voxels' own emission (an area light's leaves them).
    let mut set = voxel_settings(32, false, Mode::VoxelsRadiance);
    set.gi.area_lights = false;
    let d = render_voxels(&s, set);
    let radiance = d.radiance.as_ref().unwrap();
    let mut checked = 0;
    // The grid is padded by a voxel (origin -1/30, voxels of 1/30): the quad covers voxels 7 to
    // 24 in x and z whole; those beside it only touch its edges.
    let inside = |c: u32| (7..=24).contains(&c);
    for (i, e) in d.emission.iter().enumerate() {
        let (x, z) = (i as u32 % 32, i as u32 / (32 * 32));
        if d.filled[i] && e.x > 1.0 && inside(x) && inside(z) {
            assert!(
                (e.x - 17.0).abs() < 0.17 && (e.y - 4.0).abs() < 0.04,
                "emission {e}"
            );
            // The radiance volume holds it too (emission plus no light), in a float format.
            assert!(
                (radiance[i].x - 17.0).abs() < 0.17,
                "radiance {}",
                radiance[i]
            );
            checked += 1;
        }
    }
    assert!(checked >= 18 * 18, "only {checked} emitter voxels");
}

#[test]
fn an_emitter_against_a_ceiling_keeps_its_emission() {
    // A lamp 2 mm under a ceiling shares the ceiling's voxels; seen from below it is in front,
    // so the voxels must emit what it emits, not its mean with the ceiling's nothing.
    let n = 32;
    let le = 3.0;
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::splat(0.5));
    anchor(&mut s, m);
    emitter(&mut s, Vec3::ONE, Vec3::splat(le), false);
    // Both face down; the ceiling is larger than the lamp.
    let square = |s: &mut Scene, lo: f32, hi: f32, y: f32, material: u32| {
        let p = |x: f32, z: f32| Vec3::new(x, y, z);
        quad(s, [p(lo, lo), p(hi, lo), p(hi, hi), p(lo, hi)], material);
    };
    let (yc, yl) = (0.55, 0.548);
    square(&mut s, 0.1, 0.9, yc, m);
    square(&mut s, 0.3, 0.7, yl, 1);
    let d = render_voxels(&s, voxel_settings(n, false, Mode::VoxelsEmission));
    let grid = VoxelGrid::fit(&s.bounds, n);
    let c = |v: f32| ((v - grid.origin.x) / grid.voxel_size()) as u32;
    // A voxel inside the lamp's square and one beside it under the bare ceiling.
    let (inside, beside) = (c(0.5), c(0.2));
    let y = ((yl - grid.origin.y) / grid.voxel_size()) as u32;
    assert!(
        d.filled[d.index(inside, y, inside)],
        "the lamp's voxel is empty"
    );
    let e = d.emission[d.index(inside, y, inside)].x;
    assert!(
        (e - le).abs() < 0.01 * le,
        "the lamp's voxel emits {e}, the lamp {le}"
    );
    let e = d.emission[d.index(beside, y, beside)].x;
    assert_eq!(e, 0.0, "the bare ceiling emits {e}");
}

#[test]
fn an_emitter_holds_its_own_power_in_the_voxels() {
    // Conservative rasterization gives every voxel a surface touches a fragment; the voxels along
    // an emitter's edges must not emit as if covered whole. Power seen along the projection axis
    // (emission x a voxel's face, summed over the columns) against Le x the projected area, for
    // squares whose edges cut voxels at a fraction, flat and tilted, and one smaller than a voxel.
    let n = 32;
    let le = 5.0;
    for (lo, hi, tilt) in [(0.21, 0.79, 0.0), (0.31, 0.47, 0.3), (0.5, 0.51, 0.0)] {
        let mut s = empty_scene();
        let m = lambert(&mut s, Vec3::splat(0.5));
        anchor(&mut s, m);
        emitter(&mut s, Vec3::ZERO, Vec3::splat(le), false);
        // A square in a plane through y = 0.5, tilted about x (still projected along y).
        let p = |x: f32, z: f32| Vec3::new(x, 0.5 + tilt * (z - 0.5), z);
        quad(&mut s, [p(lo, hi), p(hi, hi), p(hi, lo), p(lo, lo)], 1);
        let d = render_voxels(&s, voxel_settings(n, false, Mode::VoxelsEmission));
        let vs = VoxelGrid::fit(&s.bounds, n).voxel_size();
        // Seen along y: each column shows its first emitting voxel (a tilted plane crosses two
        // voxels in some columns, the one behind hidden).
        let mut power = 0.0;
        for x in 0..n {
            for z in 0..n {
                let first = (0..n)
                    .map(|y| d.emission[d.index(x, y, z)].x)
                    .find(|&e| e > 0.0)
                    .unwrap_or(0.0);
                power += first * vs * vs;
            }
        }
        let want = le * (hi - lo) * (hi - lo);
        assert!(
            (power - want).abs() < 0.02 * want,
            "square {lo}..{hi} tilt {tilt}: power {power} in the voxels, {want} emitted"
        );
    }
}

#[test]
fn dynamic_node_leaves_nothing_behind_and_static_voxels_stay() {
    for paper in [false, true] {
        moving_node_leaves_nothing_behind(paper, 32, 0.0);
    }
}

#[test]
fn a_dynamic_node_at_the_far_end_of_a_large_paper_grid_leaves_nothing_behind() {
    // The paper's clear of the dynamic voxels runs one invocation per voxel: 170^3 of them is
    // more groups than one dimension of a dispatch must allow (65535 x 64 = 4.19M voxels), and
    // the node sits where the voxel index is beyond that (z near the grid's far end).
    moving_node_leaves_nothing_behind(true, 170, 0.8);
}

/// A node voxelized every frame moves across a static floor (voxels n^3, the node in the plane
/// z = `z`): the voxels at its old place empty and the floor's stay exactly as they were.
fn moving_node_leaves_nothing_behind(paper: bool, n: u32, z: f32) {
    {
        let mut s = empty_scene();
        let floor_m = lambert(&mut s, Vec3::splat(0.5));
        let box_m = lambert(&mut s, Vec3::new(0.9, 0.1, 0.1));
        floor(&mut s, 1.0, floor_m);
        // A small quad standing above the floor: the dynamic node.
        let first = s.instances.len();
        quad(
            &mut s,
            [
                Vec3::new(-0.6, 0.3, z),
                Vec3::new(-0.3, 0.3, z),
                Vec3::new(-0.3, 0.6, z),
                Vec3::new(-0.6, 0.6, z),
            ],
            box_m,
        );
        let node = s.instances[first].node;
        // Bounds that hold both places.
        s.bounds.extend(Vec3::new(1.0, 1.0, 1.0));
        let mut settings = voxel_settings(n, paper, Mode::VoxelsAlbedo);
        settings.dynamic_nodes = vec![node];
        let ctx = context();
        let stats = ctx.stats.clone();
        {
            let mut r = voxgi::render::Renderer::new(&ctx, &s, settings).unwrap();
            r.render(false).unwrap();
            let before = r.read_voxels().unwrap().unwrap();
            let red = |d: &voxgi::gi::VoxelDump| -> Vec<usize> {
                (0..d.filled.len())
                    .filter(|&i| d.filled[i] && d.albedo[i].x > 0.6 && d.albedo[i].y < 0.5)
                    .collect()
            };
            let old = red(&before);
            assert!(!old.is_empty());
            // Move it 0.9 m along +X, across the floor.
            r.set_node_transform(node, Mat4::from_translation(Vec3::new(0.9, 0.0, 0.0)));
            for _ in 0..3 {
                r.render(false).unwrap();
            }
            let after = r.read_voxels().unwrap().unwrap();
            let new = red(&after);
            assert!(!new.is_empty(), "the moved node is not voxelized");
            for i in &old {
                assert!(
                    !new.contains(i),
                    "voxel {i} still holds the node at its old place"
                );
            }
            // Static voxels (the floor) are exactly as before.
            for i in 0..before.filled.len() {
                if before.filled[i] && !old.contains(&i) {
                    assert!(after.filled[i], "static voxel {i} was cleared");
                    assert_eq!(
                        before.albedo[i], after.albedo[i],
                        "static voxel {i} changed"
                    );
                }
            }
        }
        drop(ctx);
        assert_eq!(stats.count(), 0, "{}", stats.messages().join("\n"));
    }
}

#[test]
fn emissive_strengths_survive_in_the_voxels() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/scenes/EmissiveStrengthTest/EmissiveStrengthTest.gltf");
    let s = voxgi::scene::load(&path).unwrap();
    let strongest = s
        .materials
        .iter()
        .map(|m| m.emissive.max_element())
        .fold(0.0f32, f32::max);
    assert!(
        strongest > 1.0,
        "the test scene has HDR emission ({strongest})"
    );
    let d = render_voxels(&s, voxel_settings(64, false, Mode::VoxelsEmission));
    // Voxels inside the strongest emitter's surface hold its emission exactly (no clamp to 1).
    let max = d
        .emission
        .iter()
        .map(|e| e.max_element())
        .fold(0.0f32, f32::max);
    assert!(
        (max - strongest).abs() < 0.01 * strongest,
        "brightest voxel {max}, strongest emitter {strongest}"
    );
}

#[test]
fn a_grid_past_the_storage_buffer_range_voxelizes_and_one_past_the_device_is_refused() {
    // 16384^3 needs more than any device allocates at once for its widest volume; the error
    // names the largest grid that fits (512^3 on lavapipe, which tests/hard_cases.rs renders as
    // grid-512), and one more is refused the same way.
    let s = lamp_over_floor(1.0, 0.2, 1.0, 4.0);
    let ctx = context();
    let refused = |n: u32| match voxgi::render::Renderer::new(
        &ctx,
        &s,
        voxel_settings(n, false, Mode::VoxelsAlbedo),
    ) {
        Err(voxgi::vk::VkError::GridTooLarge { largest, grid, .. }) => {
            assert_eq!(grid, n);
            Some(largest)
        }
        Err(e) => panic!("{n}^3: {e}"),
        Ok(_) => None,
    };
    let largest = refused(16384).expect("16384^3 refused");
    assert!(largest < 16384, "largest {largest}");
    assert_eq!(refused(largest + 1), Some(largest), "{}^3", largest + 1);
    // The sums are reached by address, past what a storage buffer's descriptor may span
    // (lavapipe: 128 MiB): the smallest grid whose count and albedo sums (16 bytes a voxel)
    // exceed it must work, to the last voxel.
    let range = ctx.properties.limits.max_storage_buffer_range as u64;
    let past = (1..=largest)
        .find(|&k| 16 * (k as u64).pow(3) > range)
        .unwrap_or(largest);
    drop(ctx);
    let d = render_voxels(&s, voxel_settings(past, false, Mode::VoxelsAlbedo));
    let largest = past;
    let n = largest as usize;
    assert_eq!(d.resolution, largest);
    // The floor spans the grid (less its margin) in x and z: every voxel of that square, up
    // to the grid's last rows, holds its albedo and normal.
    let floor_voxels: Vec<usize> = (0..n * n * n)
        .filter(|&v| d.filled[v] && d.normal[v].y > 0.99)
        .collect();
    for &v in &floor_voxels {
        assert!(
            (d.albedo[v] - Vec3::splat(0.8)).abs().max_element() < 0.01,
            "voxel {v}: albedo {}",
            d.albedo[v]
        );
    }
    let (xs, zs): (Vec<usize>, Vec<usize>) =
        floor_voxels.iter().map(|&v| (v % n, v / (n * n))).unzip();
    let span = |c: &[usize]| (*c.iter().min().unwrap(), *c.iter().max().unwrap());
    let ((x0, x1), (z0, z1)) = (span(&xs), span(&zs));
    assert!(
        x1 + 3 >= n && z1 + 3 >= n,
        "floor up to x {x1}, z {z1} of {n}"
    );
    assert_eq!(floor_voxels.len(), (x1 - x0 + 1) * (z1 - z0 + 1));
    // And the emission sums: the emitter's inner voxels hold its radiance.
    let brightest = d.emission.iter().map(|e| e.x).fold(0.0f32, f32::max);
    assert!(
        (brightest - 4.0).abs() < 0.04,
        "brightest voxel {brightest}"
    );
}

/// The albedo of `brdf` seen from every direction, cosine-weighted: what a surface reflects of
/// the light from a uniform sky, integrated on a grid of view and light directions.
fn hemispherical_albedo(brdf: &voxgi::reference::brdf::Brdf) -> Vec3 {
    let n = 48;
    let dir = |i: usize, j: usize| {
        // Cosine-weighted over the view, uniform over the light (then weighted by its cosine).
        let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
        (u, std::f32::consts::TAU * v)
    };
    let mut sum = Vec3::ZERO;
    for a in 0..n {
        for b in 0..n {
            let (u, phi) = dir(a, b);
            let ct = u.sqrt();
            let wo = Vec3::new(
                (1.0 - u).sqrt() * phi.cos(),
                (1.0 - u).sqrt() * phi.sin(),
                ct,
            );
            for c in 0..n {
                for d in 0..n / 4 {
                    let (ci, phi_i) = (
                        (c as f32 + 0.5) / n as f32,
                        std::f32::consts::TAU * (d as f32 + 0.5) / (n / 4) as f32,
                    );
                    let si = (1.0 - ci * ci).sqrt();
                    let wi = Vec3::new(si * phi_i.cos(), si * phi_i.sin(), ci);
                    // Uniform over the hemisphere: density 1 / (2 pi).
                    sum += brdf.eval(wo, wi) * ci * std::f32::consts::TAU;
                }
            }
        }
    }
    sum / (n * n * n * (n / 4)) as f32
}

#[test]
fn voxels_reflect_what_the_brdf_reflects_and_mark_their_mirror_lobes() {
    // Horizontal quads of base colour 0.8, each in its own layer of voxels (32^3 with a voxel
    // of padding: origin -1/30, voxels of 1/30, so y = 0.25 is the middle of layer 8).
    let base = 0.8;
    // (metallic, roughness, specularFactor, expected voxel albedo, how close, expected glossy
    // share): all the light the BRDF reflects, as the path tracer's BRDF integrates it; of it,
    // the specular lobe's part is glossy (shown to wide cones only) below roughness 0.15, none
    // of it from 0.65 up.
    let brdf = |base: f32, metallic: f32, roughness: f32| {
        let b = voxgi::reference::brdf::Brdf::new(
            Vec3::splat(base),
            metallic,
            roughness,
            1.0,
            Vec3::ONE,
        );
        hemispherical_albedo(&b).x
    };
    // A dielectric's specular layer does not depend on its base colour: what the base colour
    // adds is its diffuse albedo.
    let diffuse = brdf(base, 0.0, 0.05) - brdf(0.0, 0.0, 0.05);
    // A lobe this narrow is a mirror's, too narrow for the grid of directions above: its albedo
    // is Schlick's Fresnel term averaged over the cosine-weighted view, F0 + (1 - F0) / 21.
    let mirror = |f0: f32| f0 + (1.0 - f0) / 21.0;
    let smooth = |metallic: f32| {
        let lobe = mirror(0.04) * (1.0 - metallic) + mirror(base) * metallic;
        let all = (1.0 - metallic) * diffuse + lobe;
        (all, lobe / all)
    };
    let (metal, half, dielectric) = (smooth(1.0), smooth(0.5), smooth(0.0));
    let cases = [
        (1.0, 0.05, 1.0, metal.0, 0.02, metal.1),
        (0.5, 0.05, 1.0, half.0, 0.02, half.1),
        (0.0, 0.05, 1.0, dielectric.0, 0.01, dielectric.1),
        (0.0, 0.05, 0.0, base, 1e-3, 0.0),
        (1.0, 1.0, 1.0, brdf(base, 1.0, 1.0), 0.02, 0.0),
        (1.0, 0.7, 1.0, brdf(base, 1.0, 0.7), 0.02, 0.0),
        (0.0, 0.8, 1.0, brdf(base, 0.0, 0.8), 0.02, 0.0),
    ];
    let heights = [0.15f32, 0.25, 0.35, 0.45, 0.55, 0.65, 0.75];
    let mut s = empty_scene();
    let anchor_m = lambert(&mut s, Vec3::splat(0.5));
    anchor(&mut s, anchor_m);
    for (&(metallic, roughness, specular, _, _, _), &y) in cases.iter().zip(&heights) {
        s.materials.push(Material {
            base_color: Vec3::splat(base).extend(1.0),
            metallic,
            roughness,
            specular_factor: specular,
            ..Material::default()
        });
        let m = s.materials.len() as u32 - 1;
        square(&mut s, y, m);
    }
    for paper in [false, true] {
        let d = render_voxels(&s, voxel_settings(32, paper, Mode::VoxelsAlbedo));
        for (&(metallic, roughness, specular, expected, tol, glossy), &y) in
            cases.iter().zip(&heights)
        {
            // --paper keeps the original's base colour, gamma-encoded (in RGBA8).
            let (expected, tol, glossy) = if paper {
                (base.powf(1.0 / 2.2), 1.0 / 255.0, 0.0)
            } else {
                (expected, tol, glossy)
            };
            let layer = ((y + 1.0 / 30.0) * 30.0).floor() as u32;
            let mut checked = 0;
            // The voxels the quad covers whole: 7 to 24 in x and z.
            for z in 7..=24 {
                for x in 7..=24 {
                    let i = d.index(x, layer, z);
                    assert!(d.filled[i], "voxel ({x}, {layer}, {z}) is empty");
                    let a = d.albedo[i];
                    assert!(
                        (a - Vec3::splat(expected)).abs().max_element() <= tol,
                        "metallic {metallic}, roughness {roughness}, specularFactor {specular}, \
                         paper {paper}: voxel albedo {a}, expected {expected}"
                    );
                    assert!(
                        (d.glossy[i] - glossy).abs() <= 0.03,
                        "metallic {metallic}, roughness {roughness}, specularFactor {specular}, \
                         paper {paper}: glossy share {}, expected {glossy}",
                        d.glossy[i]
                    );
                    checked += 1;
                }
            }
            assert_eq!(checked, 18 * 18);
        }
    }
}

#[test]
fn the_readback_holds_the_directional_volumes_and_small_emitters() {
    // A 2 cm emitter over a floor on an odd grid (37^3: directional volumes of 19^3 and five
    // levels, the last texel of odd levels folded): the debug readback that the hard cases
    // check for non-finite values covers every level of the eight directional volumes and the
    // volume of small emitters' light.
    let n = 37;
    let s = lamp_over_floor(2.0, 0.01, 1.0, 1e4);
    let mut set = voxel_settings(n, false, Mode::Full);
    // The emitter stays in the voxels (as a light it would leave them).
    set.gi.area_lights = false;
    let d = render_voxels(&s, set);
    let grid = VoxelGrid::fit(&s.bounds, n);
    let m = grid.aniso_resolution();
    let per_volume: u64 = (0..grid.mip_levels())
        .map(|l| ((m >> l).max(1) as u64).pow(3))
        .sum();
    let dir = d.directional.expect("directional volumes read back");
    // Six faces, light direction and position, and the thin walls' two (a bounce reads them).
    assert_eq!(dir.len() as u64, 10 * per_volume);
    assert!(dir.iter().all(|t| t.is_finite()));
    assert!(
        dir.iter().any(|t| t.x > 0.0),
        "no light in the directional volumes"
    );
    let small = d.small_emission.expect("small emitters' volume read back");
    assert_eq!(small.len(), d.filled.len());
    // Light only where an emitter is, at most the voxel's emission (the radiance scale is 1).
    for (i, &e) in small.iter().enumerate() {
        let lum = d.emission[i].dot(Vec3::new(0.2126, 0.7152, 0.0722));
        assert!(
            e.is_finite() && e >= 0.0 && e <= lum * 1.0001 + 1e-6,
            "voxel {i}: small emitters' light {e}, emission luminance {lum}"
        );
    }
    assert!(
        small.iter().any(|&e| e > 0.0),
        "the 2 cm emitter is not small"
    );
    // Without emitters the volume is a stand-in, not read back.
    let plain = lamp_over_floor(2.0, 0.01, 1.0, 0.0);
    let d = render_voxels(&plain, voxel_settings(n, false, Mode::Full));
    assert!(d.small_emission.is_none());
    assert!(d.directional.is_some());
}

#[test]
fn a_sliver_samples_its_own_texels_not_extrapolated_ones() {
    // A texture red for v in [0, 0.5), green for [0.5, 1), repeated; a sliver triangle (a
    // ten-thousandth of a voxel high, six voxels long, turned off the axes) whose texture
    // coordinates lie in the red half. Conservative rasterization grows it by half a voxel,
    // thousands of its heights: attributes extrapolated that far read texels anywhere in the
    // texture (and took lavapipe minutes per draw for a building of such slivers).
    let mut s = empty_scene();
    let red_green = textured(
        &mut s,
        "red over green",
        1,
        2,
        vec![255, 0, 0, 255, 0, 255, 0, 255],
        Wrap::Repeat,
    );
    let grey = lambert(&mut s, Vec3::splat(0.5));
    anchor(&mut s, grey);
    let n = 32;
    let grid = VoxelGrid::fit(
        &voxgi::scene::Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        },
        n,
    );
    let vs = grid.voxel_size();
    let turn = Quat::from_rotation_y(0.3) * Quat::from_rotation_x(0.2);
    let centre = Vec3::splat(0.5);
    let corners = [
        Vec3::new(-3.0 * vs, 0.0, 0.0),
        Vec3::new(3.0 * vs, 0.0, 0.0),
        Vec3::new(0.2 * vs, 1e-4 * vs, 0.0),
    ]
    .map(|c| centre + turn * c);
    triangle(
        &mut s,
        corners,
        [[0.5, 0.1], [0.5, 0.1], [0.5, 0.4]],
        red_green,
    );
    let d = render_voxels(&s, voxel_settings(n, false, Mode::VoxelsAlbedo));
    let near = |i: usize| {
        let r = d.resolution as usize;
        let c = Vec3::new((i % r) as f32, ((i / r) % r) as f32, (i / (r * r)) as f32);
        (grid.origin + (c + 0.5) * vs - centre).length() < 5.0 * vs
    };
    let sliver: Vec<usize> = (0..d.filled.len())
        .filter(|&i| d.filled[i] && near(i))
        .collect();
    assert!(
        sliver.len() >= 6,
        "the sliver filled {} voxels",
        sliver.len()
    );
    for i in sliver {
        let a = d.albedo[i];
        assert!(
            a.x > 0.99 && a.y < 0.01,
            "voxel {i} of the sliver holds albedo {a}: texels from outside its own"
        );
    }
}

/// The original's imageAtomicRGBA8Avg applied to `values` one after another (each fragment's
/// compare-and-swap meeting the word the one before left): the word's bytes.
fn rgba8_average_model(values: &[f32]) -> [u8; 4] {
    let pack = |v: [f32; 4]| v.map(|x| (x as u32 & 0xFF) as u8);
    let mut word = [0u8; 4];
    for &x in values {
        let value = x * 255.0;
        if word == [0; 4] {
            word = pack([value, value, value, 1.0]);
            continue;
        }
        let r = word.map(|b| b as f32);
        let a = r[3] + 1.0;
        let mean = |c: usize| (r[c] * r[3] + value) / a;
        word = pack([mean(0), mean(1), mean(2), a]);
    }
    word
}

#[test]
fn paper_average_is_the_compare_and_swap_model_bit_for_bit() {
    // Varied texels, so that every round's truncation shows: the stored bytes and count are
    // those of the original's loop run on the CPU, fragment after fragment, on the gamma-space
    // values --paper writes.
    let (s, _) = stacked_triangles(&COUNTS, true, 32);
    let d = render_voxels(&s, voxel_settings(32, true, Mode::VoxelsAlbedo));
    for (k, &count) in COUNTS.iter().enumerate() {
        let c = [2 + (k as u32 % 28), 3 + 2 * (k as u32 / 28), 16];
        let values: Vec<f32> = (0..count)
            .map(|i| {
                let texel = (i * 37 + k as u32 * 11) % 256;
                (texel as f32 / 255.0).powf(1.0 / 2.2)
            })
            .collect();
        let want = rgba8_average_model(&values);
        let i = d.index(c[0], c[1], c[2]);
        let got = (d.albedo[i] * 255.0).round();
        let got = [got.x as u8, got.y as u8, got.z as u8, d.count[i] as u8];
        assert_eq!(got, want, "{count} fragments in voxel {c:?}");
    }
}

/// The thin walls (`Volumes::thin_walls`, which the bounce's cones read): a wall of one quad in
/// open space covers the base texels it passes through along x in full, and lies where the quad
/// does; texels two or more away along x hold no wall, and no texel holds a wall facing y or z.
/// Without a bounce the volumes are one-texel stand-ins, not read back.
#[test]
fn a_thin_wall_covers_its_texels_at_its_plane() {
    let n = 32;
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::splat(0.8));
    anchor(&mut s, m);
    let x = 0.53;
    quad(
        &mut s,
        [
            Vec3::new(x, 0.1, 0.1),
            Vec3::new(x, 0.9, 0.1),
            Vec3::new(x, 0.9, 0.9),
            Vec3::new(x, 0.1, 0.9),
        ],
        m,
    );
    let d = render_voxels(&s, voxel_settings(n, false, Mode::Full));
    let grid = VoxelGrid::fit(&s.bounds, n);
    let t = grid.aniso_resolution() as usize;
    let per_volume: usize = (0..grid.mip_levels())
        .map(|l| ((t >> l).max(1)).pow(3))
        .sum();
    let dir = d.directional.expect("directional volumes read back");
    assert_eq!(dir.len(), 10 * per_volume);
    let (xy, z) = (&dir[8 * per_volume..], &dir[9 * per_volume..]);
    let gx = (x - grid.origin.x) / grid.size;
    let wall = (gx * n as f32) as usize / 2;
    let (mut covered, mut clear) = (0, 0);
    for k in 0..t {
        for j in 0..t {
            // Texels whose voxels all lie inside the quad (0.1 to 0.9) along y and z.
            let inside = |c: usize| {
                let lo = grid.origin.y + (2 * c) as f32 * grid.voxel_size();
                lo > 0.1 && lo + 2.0 * grid.voxel_size() < 0.9
            };
            for i in 0..t {
                let at = i + t * (j + t * k);
                let (w, wz) = (xy[at], z[at]);
                // The anchors' tiny triangles lie in the grid's corners.
                let corner =
                    [i, j, k].iter().all(|&c| c <= 1) || [i, j, k].iter().all(|&c| c + 2 >= t);
                assert!(
                    corner || (w.w == 0.0 && wz.y == 0.0),
                    "texel {i} {j} {k}: walls facing y or z {} {}",
                    w.w,
                    wz.y
                );
                if corner {
                    continue;
                } else if i.abs_diff(wall) >= 2 {
                    assert_eq!(
                        w.y,
                        0.0,
                        "texel {i} {j} {k}, {} from the wall",
                        i.abs_diff(wall)
                    );
                    clear += 1;
                } else if i == wall && inside(j) && inside(k) {
                    assert!(w.y > 0.999, "texel {i} {j} {k}: cover {}", w.y);
                    let lies = w.x / w.y;
                    assert!(
                        (lies - gx).abs() < 0.05 / n as f32,
                        "texel {i} {j} {k}: the wall at {lies}, the quad at {gx} (grid units)"
                    );
                    covered += 1;
                }
            }
        }
    }
    assert!(covered >= 25 && clear > 1000, "{covered} {clear}");
    let mut one = voxel_settings(n, false, Mode::Full);
    one.gi.bounces = 1;
    let d = render_voxels(&s, one);
    assert_eq!(d.directional.expect("read back").len(), 8 * per_volume);
}

/// The voxels-radiance view shows a voxel's whole light, its mirror-like lobe's too, which the
/// full-resolution volume leaves out for the narrow cones: a smooth metal floor under a sun,
/// seen from above, shows the light its voxels hold (before, black).
#[test]
fn the_radiance_view_shows_a_mirrors_light() {
    let mut s = empty_scene();
    s.materials.push(Material {
        base_color: Vec3::splat(0.9).extend(1.0),
        metallic: 1.0,
        roughness: 0.05,
        specular_factor: 1.0,
        ..Material::default()
    });
    floor(&mut s, 2.0, 0);
    top_camera(&mut s, 3.0, 40.0);
    s.lights.push(light(
        voxgi::scene::LightKind::Directional,
        Vec3::splat(3.0),
        Vec3::ZERO,
        Vec3::new(0.2, -1.0, 0.1),
    ));
    let settings = voxel_settings(32, false, Mode::VoxelsRadiance);
    let d = render_voxels(&s, settings.clone());
    let radiance = d.radiance.as_ref().unwrap();
    let floor: Vec<usize> = (0..d.filled.len())
        .filter(|&i| d.filled[i] && d.normal[i].y > 0.99)
        .collect();
    assert!(!floor.is_empty());
    assert!(
        floor.iter().all(|&i| d.glossy[i] > 0.95),
        "a mirror's voxels"
    );
    let held = floor.iter().map(|&i| radiance[i].x).sum::<f32>() / floor.len() as f32;
    assert!(held > 0.1, "the floor's voxels hold {held}");
    let img = render(&s, settings);
    let shown = img.at(8, 8)[0];
    assert!(
        (shown - held).abs() < 0.05 * held,
        "the view shows {shown}, the voxels hold {held}"
    );
}
