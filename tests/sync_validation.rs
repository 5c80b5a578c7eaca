//! The harness catches hazards: omitting a barrier on purpose must be reported by
//! synchronization validation, and the same passes with their barriers must be silent.

mod gpu;
use glam::Vec3;
use gpu::*;
use gpu_allocator::MemoryLocation;
use voxgi::gi::GiSettings;
use voxgi::render::{Mode, RenderSettings, Renderer};
use voxgi::scene::{LightKind, Scene};
use voxgi::vk::{vk, Access, Buffer, Graph, ResourceStates};

/// Records `passes` into a graph (the barriers of the pass named `omit` left out) over a
/// 1 KiB transfer-target buffer; returns the validation messages seen.
fn buffer_messages(
    omit: Option<&str>,
    passes: impl FnOnce(&mut Graph, &Buffer, &ash::Device),
) -> Vec<String> {
    let ctx = context();
    let stats = ctx.stats.clone();
    {
        let buf = Buffer::new(
            &ctx,
            "hazard target",
            1024,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )
        .unwrap();
        let mut states = ResourceStates::default();
        ctx.one_shot(|cmd| {
            let mut g = Graph::new(&ctx, cmd, &mut states, None);
            g.omit_barriers_of = omit.map(String::from);
            passes(&mut g, &buf, &ctx.device);
        })
        .unwrap();
    }
    drop(ctx);
    stats.messages()
}

/// Two passes write the same buffer; returns the validation messages seen.
fn write_twice(omit: bool) -> Vec<String> {
    buffer_messages(omit.then_some("second write"), |g, buf, d| {
        g.pass("first write")
            .buffer(buf, Access::TransferWrite)
            .record(|cmd| unsafe { d.cmd_fill_buffer(cmd, buf.raw, 0, 1024, 1) });
        g.pass("second write")
            .buffer(buf, Access::TransferWrite)
            .record(|cmd| unsafe { d.cmd_fill_buffer(cmd, buf.raw, 0, 1024, 2) });
    })
}

#[test]
fn omitted_barrier_is_reported_by_synchronization_validation() {
    let clean = write_twice(false);
    assert!(clean.is_empty(), "with barriers: {clean:#?}");
    let hazard = write_twice(true);
    assert!(
        hazard
            .iter()
            .any(|m| m.contains("SYNC-HAZARD-WRITE-AFTER-WRITE") && m.contains("second write")),
        "no write-after-write hazard reported: {hazard:#?}"
    );
}

/// One pass of two steps, each writing the same buffer; returns the validation messages.
fn two_steps(omit: Option<&str>) -> Vec<String> {
    buffer_messages(omit, |g, buf, d| {
        g.pass("steps")
            .buffer(buf, Access::TransferWrite)
            .record_steps(2, |cmd, step| unsafe {
                d.cmd_fill_buffer(cmd, buf.raw, 0, 1024, step as u32)
            });
    })
}

#[test]
fn steps_of_a_pass_get_the_barriers_between_them() {
    let clean = two_steps(None);
    assert!(clean.is_empty(), "with barriers: {clean:#?}");
    let hazard = two_steps(Some("steps between steps"));
    assert!(
        hazard
            .iter()
            .any(|m| m.contains("SYNC-HAZARD-WRITE-AFTER-WRITE") && m.contains("steps")),
        "no write-after-write hazard between the steps: {hazard:#?}"
    );
}

/// A point light 1 m over the scene's floor, which the camera sees from 3 m above.
fn light_from_above(s: &mut Scene) {
    top_camera(s, 3.0, 60.0);
    s.lights.push(light(
        LightKind::Point,
        Vec3::splat(5.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::NEG_Y,
    ));
}

/// One frame of `s` at 32x32 with `settings`' mode and voxels, the barriers of the pass
/// `omit` left out; returns the validation messages.
fn renderer_messages(s: &Scene, settings: RenderSettings, omit: Option<&str>) -> Vec<String> {
    let ctx = context();
    let stats = ctx.stats.clone();
    {
        let settings = RenderSettings {
            width: 32,
            height: 32,
            shadow_resolution: 64,
            ..settings
        };
        let mut r = Renderer::new(&ctx, s, settings).unwrap();
        r.omit_barriers_of = omit.map(String::from);
        r.render(true).unwrap();
    }
    drop(ctx);
    stats.messages()
}

#[test]
fn renderer_pass_without_its_barriers_is_reported() {
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::splat(0.5));
    floor(&mut s, 2.0, m);
    light_from_above(&mut s);
    let direct = RenderSettings {
        mode: Mode::Direct,
        ..Default::default()
    };
    let msgs = renderer_messages(&s, direct, Some("lighting"));
    assert!(
        msgs.iter().any(|m| m.contains("SYNC-HAZARD")),
        "no hazard reported without the lighting pass's barriers: {msgs:#?}"
    );
}

/// Two overlapping floors voxelized by --paper (two draws averaging into the same r32ui
/// images), a small moving quad above them (so the static draws write the static flags), and
/// a point light; the barriers of the pass `omit` left out. Returns the messages.
fn paper_frame(omit: Option<&str>) -> Vec<String> {
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::splat(0.5));
    floor(&mut s, 2.0, m);
    floor(&mut s, 1.0, m);
    let (a, b) = (0.3, 0.5);
    quad(
        &mut s,
        [
            Vec3::new(-a, b, a),
            Vec3::new(a, b, a),
            Vec3::new(a, b, -a),
            Vec3::new(-a, b, -a),
        ],
        m,
    );
    light_from_above(&mut s);
    let paper = RenderSettings {
        gi: GiSettings::paper(16),
        dynamic_nodes: vec![s.instances[2].node],
        ..Default::default()
    };
    renderer_messages(&s, paper, omit)
}

/// Whether a message reports a hazard of `kind` on the image named `image` (through any of
/// its views: "[voxel albedo]", "[voxel albedo as R8G8B8A8_UNORM]").
fn hazard_on(msgs: &[String], kind: &str, image: &str) -> bool {
    let named =
        |m: &String| m.contains(&format!("[{image}]")) || m.contains(&format!("[{image} as "));
    msgs.iter().any(|m| m.contains(kind) && named(m))
}

#[test]
fn paper_voxel_images_are_seen_by_synchronization_validation() {
    let clean = paper_frame(None);
    assert!(clean.is_empty(), "with barriers: {clean:#?}");
    // The draws averaging into the volumes (and storing the static flags) with no barrier
    // after their clear.
    let draws = paper_frame(Some("voxelize static"));
    for image in ["voxel albedo", "voxel normal"] {
        assert!(
            hazard_on(&draws, "SYNC-HAZARD-READ-AFTER-WRITE", image),
            "no hazard on the draws' atomics on {image}: {draws:#?}"
        );
    }
    assert!(
        hazard_on(&draws, "SYNC-HAZARD-WRITE-AFTER-WRITE", "static flags"),
        "no hazard on the draws' flags: {draws:#?}"
    );
    // Injection reading the averages with no barrier after the draws.
    let read = paper_frame(Some("inject"));
    assert!(
        hazard_on(&read, "SYNC-HAZARD-READ-AFTER-WRITE", "voxel albedo"),
        "no hazard on reading the paper's voxels: {read:#?}"
    );
}
