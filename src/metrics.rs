//! Error between an image and a reference, as CONVENTIONS.md defines it: relMSE, mean absolute
//! error and RMSE on the linear radiance, and FLIP (Andersson et al. 2020, NVIDIA's
//! implementation through the `nv-flip` crate) on the display images.

use crate::output::{display, RadianceImage};

/// relMSE's denominator term: keeps near-black reference pixels from dominating.
pub const REL_MSE_EPSILON: f64 = 0.01;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    /// Mean over pixels and channels of (A - R)^2 / (R^2 + 0.01).
    pub rel_mse: f64,
    /// Mean over pixels and channels of |A - R|.
    pub mae: f64,
    /// Square root of the mean over pixels and channels of (A - R)^2.
    pub rmse: f64,
    /// Mean LDR-FLIP error of the two display images (0 = identical, 1 = most different).
    pub flip: f64,
}

impl Metrics {
    /// One line of JSON with the four metrics.
    pub fn to_json(&self) -> String {
        let num = |v: f64| {
            if v.is_finite() {
                format!("{v:e}")
            } else {
                "null".to_string()
            }
        };
        format!(
            "{{\"relMSE\":{},\"MAE\":{},\"RMSE\":{},\"FLIP\":{}}}",
            num(self.rel_mse),
            num(self.mae),
            num(self.rmse),
            num(self.flip)
        )
    }
}

#[derive(Debug, thiserror::Error)]
pub enum MetricsError {
    #[error("the images differ in size: {a_w}x{a_h} against the reference's {r_w}x{r_h}")]
    Size {
        a_w: u32,
        a_h: u32,
        r_w: u32,
        r_h: u32,
    },
    #[error("the {which} image has {count} NaN or infinite values")]
    NonFinite { which: &'static str, count: usize },
    #[error("the images are empty")]
    Empty,
}

/// Compares `a` with `reference`; FLIP uses the display images at exposure 0.
///
/// # Panics
/// If the sizes differ or a pixel is not finite; [`try_compare`] reports those as errors.
pub fn compare(a: &RadianceImage, reference: &RadianceImage) -> Metrics {
    try_compare(a, reference, 0.0).unwrap_or_else(|e| panic!("compare: {e}"))
}

/// Compares `a` with `reference`; both display images for FLIP use `exposure` (stops).
pub fn try_compare(
    a: &RadianceImage,
    reference: &RadianceImage,
    exposure: f32,
) -> Result<Metrics, MetricsError> {
    if (a.width, a.height) != (reference.width, reference.height)
        || a.pixels.len() != reference.pixels.len()
    {
        return Err(MetricsError::Size {
            a_w: a.width,
            a_h: a.height,
            r_w: reference.width,
            r_h: reference.height,
        });
    }
    if a.pixels.is_empty() {
        return Err(MetricsError::Empty);
    }
    for (which, img) in [("compared", a), ("reference", reference)] {
        let count = img
            .pixels
            .iter()
            .flatten()
            .filter(|v| !v.is_finite())
            .count();
        if count > 0 {
            return Err(MetricsError::NonFinite { which, count });
        }
    }
    let (mut abs, mut sq) = (0.0f64, 0.0f64);
    for (pa, pr) in a.pixels.iter().zip(&reference.pixels) {
        for (&va, &vr) in pa.iter().zip(pr) {
            let e = va as f64 - vr as f64;
            abs += e.abs();
            sq += e * e;
        }
    }
    let n = (a.pixels.len() * 3) as f64;
    Ok(Metrics {
        rel_mse: rel_mse(a, reference, 1.0),
        mae: abs / n,
        rmse: (sq / n).sqrt(),
        flip: flip(a, reference, exposure),
    })
}

/// relMSE of `a` against `reference` (same size), both scaled by `scale` first: at a display
/// exposure of 2^e, `scale` = 2^e.
pub fn rel_mse(a: &RadianceImage, reference: &RadianceImage, scale: f64) -> f64 {
    let mut rel = 0.0f64;
    for (pa, pr) in a.pixels.iter().zip(&reference.pixels) {
        for (&va, &vr) in pa.iter().zip(pr) {
            let (va, vr) = (va as f64 * scale, vr as f64 * scale);
            rel += (va - vr) * (va - vr) / (vr * vr + REL_MSE_EPSILON);
        }
    }
    rel / (a.pixels.len() * 3).max(1) as f64
}

/// Mean FLIP error between the display images of `a` and `reference` (same size).
pub fn flip(a: &RadianceImage, reference: &RadianceImage, exposure: f32) -> f64 {
    flip_display(&display(a, exposure), &display(reference, exposure))
}

/// Mean FLIP error between two display images (8-bit sRGB, same size), e.g. PNG files.
pub fn flip_display(a: &image::RgbImage, reference: &image::RgbImage) -> f64 {
    let to_flip =
        |d: &image::RgbImage| nv_flip::FlipImageRgb8::with_data(d.width(), d.height(), d.as_raw());
    let error = nv_flip::flip(
        to_flip(reference),
        to_flip(a),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let values = error.to_vec();
    values.iter().map(|&v| v as f64).sum::<f64>() / values.len().max(1) as f64
}
