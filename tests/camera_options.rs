//! `--camera NAME|INDEX` and `--eye/--target/--up/--fov`: a file's camera picked by name and by
//! index, and an eye and a target equal to that camera giving the same image.

mod common;
use common::{temp_dir, voxgi};
use glam::{Mat4, Vec3};
use voxgi::hard::scenes::{room, RoomLight};
use voxgi::scene::builder::{CameraDesc, NodeDesc};

const SIDE_EYE: [f32; 3] = [0.9, 1.3, 2.6];
const SIDE_TARGET: [f32; 3] = [-0.2, 0.7, -0.4];

/// The hard cases' room with two cameras: "front" (met first, so the default view) and
/// "side", placed by a look-at matrix.
fn room_with_cameras(dir: &std::path::Path) -> std::path::PathBuf {
    let (mut b, _) = room(RoomLight::Point(2.0));
    let cam = |name: &str, yfov: f32| CameraDesc {
        name: Some(name.into()),
        yfov,
        znear: 0.01,
        zfar: None,
        aspect_ratio: Some(1.0),
    };
    let front = b.add_camera(cam("front", 0.7));
    let side = b.add_camera(cam("side", 0.9));
    let place = |eye: [f32; 3], target: [f32; 3]| {
        Mat4::look_at_rh(Vec3::from(eye), Vec3::from(target), Vec3::Y)
            .inverse()
            .to_cols_array()
    };
    b.add_node(
        NodeDesc::new("front camera")
            .camera(front)
            .matrix(place([0.0, 1.0, 3.4], [0.0, 1.0, 0.0])),
    );
    b.add_node(
        NodeDesc::new("side camera")
            .camera(side)
            .matrix(place(SIDE_EYE, SIDE_TARGET)),
    );
    let path = dir.join("room.gltf");
    b.write(&path).unwrap();
    path
}

fn render(scene: &std::path::Path, out: &std::path::Path, view: &[&str]) -> Vec<[f32; 3]> {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "32",
        "--voxels",
        "32",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(view);
    let (ok, stdout, stderr) = voxgi(&args);
    assert!(ok, "{view:?}: {stdout}\n{stderr}");
    voxgi::output::load_exr(out).unwrap().pixels
}

fn csv(v: [f32; 3]) -> String {
    format!("{},{},{}", v[0], v[1], v[2])
}

#[test]
fn a_camera_by_name_by_index_and_by_eye_and_target_give_one_image() {
    let dir = temp_dir("camera-options");
    let scene = room_with_cameras(&dir);
    let default = render(&scene, &dir.join("default.exr"), &[]);
    let front = render(&scene, &dir.join("front.exr"), &["--camera", "front"]);
    assert_eq!(default, front, "the default view is the first camera met");
    let by_name = render(&scene, &dir.join("side.exr"), &["--camera", "side"]);
    let by_index = render(&scene, &dir.join("side1.exr"), &["--camera", "1"]);
    assert_eq!(by_name, by_index);
    assert_ne!(
        by_name, front,
        "the side camera sees the same image as the front one"
    );
    let (eye, target) = (csv(SIDE_EYE), csv(SIDE_TARGET));
    let fov = 0.9f32.to_degrees().to_string();
    let looked = render(
        &scene,
        &dir.join("eye.exr"),
        &["--eye", &eye, "--target", &target, "--fov", &fov],
    );
    // The same camera up to the rounding of its matrix and of the field of view.
    let mut worst = 0.0f32;
    for (a, b) in looked.iter().zip(&by_name) {
        for k in 0..3 {
            worst = worst.max((a[k] - b[k]).abs() / (b[k].abs() + 0.01));
        }
    }
    assert!(
        worst < 1e-3,
        "--eye/--target against --camera side: {worst}"
    );
}

#[test]
fn camera_options_that_cannot_be_honoured_are_clear_errors() {
    let dir = temp_dir("camera-errors");
    let scene = room_with_cameras(&dir);
    let s = scene.to_str().unwrap();
    for (args, want) in [
        (
            vec!["--camera", "top"],
            "no camera \"top\" (the cameras its nodes use: 0 (\"front\"), 1 (\"side\"))",
        ),
        (vec!["--camera", "7"], "no camera \"7\""),
        (vec!["--eye", "0,1,2"], "--target"),
        (
            vec!["--eye", "0,1,2", "--target", "0,1,2"],
            "--target must differ from --eye",
        ),
        (vec!["--eye", "0,1,2", "--target", "0,1,x"], "X,Y,Z"),
        (
            vec!["--eye", "0,1,2", "--target", "0,0,0", "--fov", "200"],
            "--fov",
        ),
        (
            vec!["--camera", "side", "--eye", "0,1,2", "--target", "0,0,0"],
            "--camera",
        ),
    ] {
        let out = dir.join("x.exr");
        let mut all = vec![
            "render",
            s,
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            out.to_str().unwrap(),
        ];
        all.extend(args.iter().copied());
        let (ok, _, stderr) = voxgi(&all);
        assert!(!ok, "{args:?} succeeded");
        assert!(stderr.contains(want), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
        assert!(!out.exists(), "{args:?} wrote an image");
    }
}

#[test]
fn every_command_that_renders_takes_the_camera_options() {
    for cmd in ["render", "view", "reference", "bench", "info", "soak"] {
        let (ok, stdout, _) = voxgi(&[cmd, "--help"]);
        assert!(ok);
        for opt in ["--camera", "--eye", "--target", "--up", "--fov"] {
            assert!(stdout.contains(opt), "{cmd} lacks {opt}");
        }
    }
}
