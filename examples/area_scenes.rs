//! Writes the area lights' test scenes as .glb files, for `voxgi render` and `voxgi bench`
//! (docs/area-lights.md): the Cornell box lit by its ceiling quad, the room lit by four small
//! emitters, and rooms lit by 1 to 32 emissive spheres (the cost as emitters are added).
//!
//!     cargo run --release --example area_scenes -- OUT_DIR

use std::path::PathBuf;
use voxgi::hard::scenes::{cornell_quad_light, emitter_grid, emitter_room};

fn main() -> std::io::Result<()> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "area-scenes".into()),
    );
    std::fs::create_dir_all(&dir)?;
    let mut scenes = vec![
        ("area-cornell".to_string(), cornell_quad_light().0),
        ("area-room".to_string(), emitter_room().0),
    ];
    for n in [1, 2, 4, 8, 16, 32] {
        scenes.push((format!("emitters-{n}"), emitter_grid(n).0));
    }
    for (name, b) in scenes {
        let path = dir.join(format!("{name}.glb"));
        std::fs::write(&path, b.to_glb())?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
