//! The image metrics of CONVENTIONS.md: zero for identical images, the known value for a known
//! perturbation, and clear errors for images that cannot be compared.

use voxgi::metrics::{compare, try_compare, MetricsError};
use voxgi::output::RadianceImage;

/// A smooth image with values from 0 to about 3, so relMSE's 0.01 term matters at the dark end.
fn gradient(w: u32, h: u32) -> RadianceImage {
    let pixels = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
            [x * 3.0, y, (x * y * 6.0).sin().abs()]
        })
        .collect();
    RadianceImage {
        width: w,
        height: h,
        pixels,
    }
}

#[test]
fn identical_images_have_zero_error() {
    let r = gradient(40, 30);
    let m = compare(&r, &r);
    assert_eq!((m.rel_mse, m.mae, m.rmse, m.flip), (0.0, 0.0, 0.0, 0.0));
}

#[test]
fn a_constant_offset_gives_its_known_errors() {
    let r = gradient(40, 30);
    let c = 0.125f32;
    let a = RadianceImage {
        pixels: r.pixels.iter().map(|p| p.map(|v| v + c)).collect(),
        ..r.clone()
    };
    // By hand: every difference is c.
    let n = (r.pixels.len() * 3) as f64;
    let c2 = (c as f64) * (c as f64);
    let rel: f64 = r
        .pixels
        .iter()
        .flatten()
        .map(|&v| c2 / ((v as f64) * (v as f64) + 0.01))
        .sum::<f64>()
        / n;
    let m = compare(&a, &r);
    assert!((m.mae - c as f64).abs() < 1e-6, "MAE {}", m.mae);
    assert!((m.rmse - c as f64).abs() < 1e-6, "RMSE {}", m.rmse);
    // f32 rounding of R + c leaves the differences within a few 1e-7 of c.
    assert!(
        (m.rel_mse - rel).abs() < 1e-5 * rel,
        "relMSE {} against {rel}",
        m.rel_mse
    );
    assert!(m.flip > 0.0 && m.flip < 1.0, "FLIP {}", m.flip);

    // relMSE divides by the reference: swapping the images changes it, not MAE or RMSE.
    let swapped = compare(&r, &a);
    assert!((swapped.mae - m.mae).abs() < 1e-9 && (swapped.rmse - m.rmse).abs() < 1e-9);
    assert!(swapped.rel_mse < m.rel_mse);
}

#[test]
fn a_single_changed_pixel() {
    let mut r = gradient(10, 10);
    r.pixels[0] = [1.0, 1.0, 1.0];
    let mut a = r.clone();
    a.pixels[0] = [3.0, 1.0, 1.0];
    let m = compare(&a, &r);
    // One of 300 values is off by 2: (A - R)^2 / (R^2 + 0.01) = 4 / 1.01.
    assert!((m.rel_mse - 4.0 / 1.01 / 300.0).abs() < 1e-9);
    assert!((m.mae - 2.0 / 300.0).abs() < 1e-9);
    assert!((m.rmse - (4.0f64 / 300.0).sqrt()).abs() < 1e-9);
}

#[test]
fn flip_grows_with_the_difference_and_sees_exposure() {
    let r = gradient(64, 64);
    let scaled = |k: f32| RadianceImage {
        pixels: r.pixels.iter().map(|p| p.map(|v| v * k)).collect(),
        ..r.clone()
    };
    let small = try_compare(&scaled(1.05), &r, 0.0).unwrap().flip;
    let large = try_compare(&scaled(1.5), &r, 0.0).unwrap().flip;
    assert!(
        0.0 < small && small < large && large < 1.0,
        "{small} {large}"
    );
    // Deep underexposure crushes both display images to black: FLIP sees nothing.
    let dark = try_compare(&scaled(1.5), &r, -30.0).unwrap();
    assert_eq!(dark.flip, 0.0);
    assert!(dark.rel_mse > 0.0);
}

#[test]
fn bad_input_is_an_error() {
    let r = gradient(8, 8);
    let other = gradient(8, 9);
    assert!(matches!(
        try_compare(&other, &r, 0.0),
        Err(MetricsError::Size { .. })
    ));
    let mut nan = r.clone();
    nan.pixels[3][1] = f32::NAN;
    let e = try_compare(&nan, &r, 0.0).unwrap_err();
    assert!(e.to_string().contains("NaN"), "{e}");
    assert!(try_compare(&r, &nan, 0.0).is_err());
}

#[test]
fn json_line_has_the_four_keys() {
    let r = gradient(16, 16);
    let a = RadianceImage {
        pixels: r.pixels.iter().map(|p| p.map(|v| v * 0.9)).collect(),
        ..r.clone()
    };
    let m = compare(&a, &r);
    let line = m.to_json();
    assert!(!line.contains('\n'));
    let v: serde_json::Value = serde_json::from_str(&line).unwrap();
    assert_eq!(v["relMSE"].as_f64(), Some(m.rel_mse));
    assert_eq!(v["MAE"].as_f64(), Some(m.mae));
    assert_eq!(v["RMSE"].as_f64(), Some(m.rmse));
    assert_eq!(v["FLIP"].as_f64(), Some(m.flip));
}
