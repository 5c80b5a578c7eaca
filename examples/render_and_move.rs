//! The crate as a library: load a glTF scene, render it to an EXR, move a node and render
//! again.
//!
//! ```sh
//! cargo run --release --example render_and_move -- [SCENE.gltf] [NODE]
//! ```
//!
//! Without arguments: the bundled Cornell box (assets/) and its "tall box". Writes
//! before.exr and after.exr in the working directory.

use anyhow::{anyhow, Context as _, Result};
use glam::Vec3;
use std::path::PathBuf;
use voxgi::output::{self, RadianceImage};
use voxgi::render::{RenderSettings, Renderer};
use voxgi::scene::{self, Motion, Spin};
use voxgi::vk::{Context, ContextDesc};

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let path = args.next().map(PathBuf::from).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.gltf")
    });
    let node_name = args.next().unwrap_or_else(|| "tall box".to_string());

    // The scene, and the node that will move: voxelized every frame into the dynamic voxels
    // (declared before the renderer is made, so that the grid covers where it goes).
    let mut scene = scene::load(&path).with_context(|| format!("loading {}", path.display()))?;
    let node = scene.node_named(&node_name).map_err(|e| anyhow!(e))?;
    let motion = Motion {
        spin: Some(Spin {
            node,
            degrees_per_second: 90.0,
        }),
        animate: false,
    };
    let settings = RenderSettings {
        width: 256,
        height: 256,
        dynamic_nodes: motion.prepare(&mut scene),
        ..Default::default()
    };

    let ctx = Context::new(&ContextDesc::default())?;
    println!("device: {}", ctx.device_info);
    let mut renderer = Renderer::new(&ctx, &scene, settings)?;
    let frame = |renderer: &mut Renderer, out: &str| -> Result<()> {
        // The antialiasing mean of 8 frames, read back after the last.
        for f in 0..8 {
            renderer.render(f == 7)?;
        }
        let image = RadianceImage {
            width: 256,
            height: 256,
            pixels: renderer.radiance(),
        };
        output::save(&image, out.as_ref(), 0.0)?;
        let mean: Vec3 =
            image.pixels.iter().map(|p| Vec3::from(*p)).sum::<Vec3>() / image.pixels.len() as f32;
        println!(
            "wrote {out} (mean radiance {:.4})",
            mean.x + mean.y + mean.z
        );
        Ok(())
    };
    frame(&mut renderer, "before.exr")?;
    // A quarter of a second of the spin: 22.5 degrees about the node's vertical axis.
    for (n, world) in motion.pose(&scene, 0.25) {
        renderer.set_node_transform(n, world);
    }
    frame(&mut renderer, "after.exr")?;
    Ok(())
}
