//! The hard cases of `voxgi::hard` (docs/hard-cases.md), one test each, at the default settings
//! on a small image and grid under the validation layer. Every case must stay finite (images and
//! volumes) and free of validation messages, and meet its goal.

mod gpu;

use std::sync::Mutex;
use voxgi::hard::{Env, CASES};

/// Image side, grid side and reference samples per pixel of the tests (the report uses 64, 64,
/// 256: `voxgi hard-cases`). With 64 samples the reference's noise alone came to about 0.02 of
/// the rooms' relMSE and favoured darker images (where the noisy reference is dark the error
/// weighs most).
const SIZE: u32 = 48;
const VOXELS: u32 = 64;
const REF_SPP: u32 = 256;

/// One validated context for all cases: lavapipe's instance creation is slow and the cases run
/// one at a time anyway (each renders at 48x48 and path-traces a reference on both cores).
static ENV: Mutex<Option<Env>> = Mutex::new(None);

fn check(name: &str) {
    check_below(name, None)
}

/// As [`check`], but for a case whose goal is still open (docs/hard-cases.md, "Open"): its
/// value must stay at or below `bound`, today's measurement at this size, so that it cannot
/// get worse unseen.
fn check_open(name: &str, bound: f64) {
    check_below(name, Some(bound))
}

fn check_below(name: &str, open_bound: Option<f64>) {
    let case = CASES
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no hard case {name}"));
    let mut guard = ENV.lock().unwrap_or_else(|e| e.into_inner());
    let env = guard
        .get_or_insert_with(|| Env::new(gpu::context(), SIZE, VOXELS, REF_SPP).expect("scratch"));
    let default = env.run(case, &env.settings(false));
    assert_eq!(
        default.validation_messages,
        0,
        "{name}: validation messages:\n{}",
        env.ctx.stats.messages().join("\n")
    );
    if let Some(e) = &default.error {
        panic!("{name}: {e}");
    }
    assert!(
        default.non_finite.is_empty(),
        "{name}: {:?}",
        default.non_finite
    );
    assert!(default.value.is_finite(), "{name}: value {}", default.value);
    if let Some(bound) = open_bound {
        assert!(
            !case.goal.met(default.value),
            "{name}: {} {} meets the goal {}: test it with check()",
            case.metric,
            default.value,
            case.goal
        );
        assert!(
            default.value <= bound,
            "{name}: {} {} is worse than the {bound} measured when its goal was left open",
            case.metric,
            default.value
        );
        return;
    }
    assert!(
        case.goal.met(default.value),
        "{name}: {} {} misses the goal {}",
        case.metric,
        default.value,
        case.goal
    );
}

#[test]
fn the_tail_continues_only_the_last_bounces_own_light() {
    // The furnace (albedo 0.5, Le = 1, exactly 2): the tail adds the bounces not traced as a
    // geometric series of the last one's. The last bounce's light holds every order up to it,
    // the earlier ones traced already, so only its own order may be continued: then the answer
    // hardly depends on how many bounces are traced. Measured (48x48) 0.0251, 0.0260 and
    // 0.0264 of the exact value with 2, 3 and 4 (64x64: 0.0278, 0.0287, 0.0291); continuing all
    // of the last bounce's light gave, at 64x64, 0.0278, 0.0234 and 0.0481 (and sky-room 0.023,
    // 0.078, 0.136).
    let case = CASES.iter().find(|c| c.name == "furnace").unwrap();
    let mut guard = ENV.lock().unwrap_or_else(|e| e.into_inner());
    let env = guard
        .get_or_insert_with(|| Env::new(gpu::context(), SIZE, VOXELS, REF_SPP).expect("scratch"));
    let errors: Vec<f64> = [2u32, 3, 4]
        .iter()
        .map(|&b| {
            let gi = voxgi::gi::GiSettings {
                bounces: b,
                ..env.settings(false)
            };
            env.run(case, &gi).value
        })
        .collect();
    eprintln!("furnace with the tail, 2 to 4 bounces: {errors:?}");
    for (b, e) in [3, 4].iter().zip(&errors[1..]) {
        assert!(
            (e - errors[0]).abs() < 0.005 && *e <= 0.05,
            "{b} bounces: {e}, 2 bounces: {}",
            errors[0]
        );
    }
}

#[test]
fn the_ideal_column_is_the_path_tracer_with_the_same_bounces() {
    // The furnace (albedo 0.5, Le = 1): with B bounces a perfect tracer gets
    // 1 + 0.5 + ... + 0.5^B of the exact 2, a relative error of 0.5^(B + 1). The defaults
    // without the tail trace those B bounces and no more, with the walls' emission in the
    // voxels (as area lights their light on the pixels is direct light, and the voxels'
    // bounces add one reflection more than the path tracer's B gives an emitter's).
    let case = CASES.iter().find(|c| c.name == "furnace").unwrap();
    let mut guard = ENV.lock().unwrap_or_else(|e| e.into_inner());
    let env = guard
        .get_or_insert_with(|| Env::new(gpu::context(), SIZE, VOXELS, REF_SPP).expect("scratch"));
    let mut rows = Vec::new();
    for b in [1u32, 2] {
        let gi = voxgi::gi::GiSettings {
            bounces: b,
            tail: false,
            area_lights: false,
            ..env.settings(false)
        };
        // Set for this run only: the other cases share the environment.
        env.ideal = true;
        let default = env.run(case, &gi);
        env.ideal = false;
        let ideal = default.ideal.expect("no ideal value");
        let want = 0.5f64.powi(b as i32 + 1);
        assert!(
            (ideal - want).abs() < 0.01,
            "{b} bounces: the path tracer's error {ideal}, exactly {want}"
        );
        assert!(
            default.value >= ideal,
            "{b} bounces: {} beats the ideal",
            default.value
        );
        // The real-time image against that path tracer's: what is left is the cones' own
        // error, far less than what the missing bounces cost (the relative error squared).
        let cones = default.cones.expect("no error against the ideal");
        assert!(
            cones > 0.0 && cones < default.value * default.value,
            "{b} bounces: relMSE {cones} against the path tracer with as many bounces, {} \
             against the exact answer",
            default.value
        );
        env.ideal = true;
        let paper = env.run(case, &env.settings(true));
        env.ideal = false;
        assert!(paper.ideal.is_none(), "--paper got an ideal value");
        assert!(
            paper.cones.is_none(),
            "--paper got an error against the ideal"
        );
        rows.push(voxgi::hard::Row {
            case,
            paper,
            default,
        });
    }
    // With the tail the 2 bounces beat the path tracer limited to 2 (it adds the bounces
    // after them), and the cones' column is still that of the image without it.
    env.ideal = true;
    let with_tail = voxgi::gi::GiSettings {
        area_lights: false,
        ..env.settings(false)
    };
    let tail = env.run(case, &with_tail);
    env.ideal = false;
    let (ideal, cones) = (tail.ideal.unwrap(), tail.cones.unwrap());
    assert!(
        tail.value < ideal,
        "with the tail {} against the 2-bounce path tracer's {ideal}",
        tail.value
    );
    let without = rows[1].default.cones.unwrap();
    assert!(
        (cones - without).abs() <= 1e-6 * without,
        "the cones' column with the tail {cones}, without {without}"
    );
    let table = voxgi::hard::table(&rows, "default", true);
    assert!(
        table
            .lines()
            .next()
            .unwrap()
            .ends_with("| path tracer, same bounces |"),
        "{table}"
    );
    for (line, row) in table.lines().skip(2).zip(&rows) {
        let cells = format!(
            "| {:.4} | {:.4} |",
            row.default.cones.unwrap(),
            row.default.ideal.unwrap()
        );
        assert!(line.ends_with(&cells), "{line} does not end with {cells}");
    }
}

/// door-room's goal (0.05) is open (docs/hard-cases.md, "Open"): 0.4402 at 64x64, 0.4357 at
/// the tests' 48x48. The room lit through the door gets its light after two bounces and
/// more, and a path tracer limited to the defaults' two bounces scores 0.606 itself (0.140
/// with eight).
#[test]
fn door_room() {
    check_open("door-room", 0.44)
}

/// sky-room's goal (0.02) is met at 64x64 (0.0162) and at issue 31's 256x256
/// (docs/environment.md), not at the tests' 48x48: 0.0231. sky-room-outward (its walls facing
/// out) meets it here since the tail's series weighs its voxels by their light (0.0259 ->
/// 0.0183; before the voxels held their backs' light, 0.0818).
#[test]
fn sky_room() {
    check_open("sky-room", 0.024)
}

macro_rules! cases {
    ($($f:ident => $name:literal,)*) => {
        $(#[test] fn $f() { check($name) })*

        #[test]
        fn every_case_has_a_test() {
            let tested = [$($name,)* "door-room", "sky-room"];
            for c in CASES {
                assert!(tested.contains(&c.name), "no test for the hard case {}", c.name);
            }
        }
    };
}

cases! {
    leak_wall_0 => "leak-wall-0",
    leak_wall_1cm => "leak-wall-1cm",
    leak_floor_1cm => "leak-floor-1cm",
    leak_wall_bounce => "leak-wall-bounce",
    leak_junction => "leak-junction",
    density_300 => "density-300",
    density_3000 => "density-3000",
    two_sided_panel => "two-sided-panel",
    scale_1mm => "scale-1mm",
    scale_10km => "scale-10km",
    translated_1e5 => "translated-1e5",
    near_light_1e5 => "near-light-1e5",
    near_light_1e6 => "near-light-1e6",
    rotated_1e_6 => "rotated-1e-6",
    degenerate => "degenerate",
    light_zero => "light-zero",
    light_1e6 => "light-1e6",
    light_inside_geometry => "light-inside-geometry",
    spot_hard_edge => "spot-hard-edge",
    sun_along_axis => "sun-along-axis",
    sun_grazing => "sun-grazing",
    emissive_1e4 => "emissive-1e4",
    area_cornell => "area-cornell",
    area_room => "area-room",
    emissive_dynamic => "emissive-dynamic",
    grazing_surfaces => "grazing-surfaces",
    cones_leave_grid => "cones-leave-grid",
    sky_yard => "sky-yard",
    sky_room_outward => "sky-room-outward",
    camera_in_volume => "camera-in-volume",
    camera_in_voxel => "camera-in-voxel",
    grid_48 => "grid-48",
    grid_100 => "grid-100",
    grid_8 => "grid-8",
    grid_512 => "grid-512",
    empty_scene => "empty-scene",
    single_triangle => "single-triangle",
    no_light => "no-light",
    furnace => "furnace",
}
