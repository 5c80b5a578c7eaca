//! The harness catches hazards: omitting a barrier on purpose must be reported by
//! synchronization validation, and the same passes with their barriers must be silent.

mod gpu;
use glam::Vec3;
use gpu::*;
use gpu_allocator::MemoryLocation;
use voxgi::render::{Mode, RenderSettings, Renderer};
use voxgi::scene::LightKind;
use voxgi::vk::{vk, Access, Buffer, Graph, ResourceStates};

/// Two passes write the same buffer; returns the validation messages seen.
fn write_twice(omit: bool) -> Vec<String> {
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
            if omit {
                g.omit_barriers_of = Some("second write".into());
            }
            g.pass("first write")
                .buffer(&buf, Access::TransferWrite)
                .record(|cmd| unsafe { ctx.device.cmd_fill_buffer(cmd, buf.raw, 0, 1024, 1) });
            g.pass("second write")
                .buffer(&buf, Access::TransferWrite)
                .record(|cmd| unsafe { ctx.device.cmd_fill_buffer(cmd, buf.raw, 0, 1024, 2) });
        })
        .unwrap();
    }
    drop(ctx);
    stats.messages()
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

#[test]
fn renderer_pass_without_its_barriers_is_reported() {
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::splat(0.5));
    floor(&mut s, 2.0, m);
    top_camera(&mut s, 3.0, 60.0);
    s.lights.push(light(
        LightKind::Point,
        Vec3::splat(5.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::NEG_Y,
    ));
    let ctx = context();
    let stats = ctx.stats.clone();
    {
        let settings = RenderSettings {
            width: 32,
            height: 32,
            shadow_resolution: 64,
            mode: Mode::Direct,
            ..Default::default()
        };
        let mut r = Renderer::new(&ctx, &s, settings).unwrap();
        r.omit_barriers_of = Some("lighting".into());
        r.render(true).unwrap();
    }
    drop(ctx);
    let msgs = stats.messages();
    assert!(
        msgs.iter().any(|m| m.contains("SYNC-HAZARD")),
        "no hazard reported without the lighting pass's barriers: {msgs:#?}"
    );
}
