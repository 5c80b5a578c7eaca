//! Fits the linearly-transformed-cosine (LTC) table of the specular lobe of glsl/brdf.glsl
//! (Heitz, Dupuy, Hill and Neubelt 2016, "Real-Time Polygonal-Light Shading with Linearly
//! Transformed Cosines") and writes it in the format that src/render/ltc.rs documents and reads.
//!
//!     cargo run --release --example fit_ltc -- assets/ltc_ggx.bin
//!
//! The lobe fitted, for the view direction v = (sin t, 0, cos t) (normal +z), is
//!     rho(l) = D(h) V(l, v) max(n.l, 0),
//! D the GGX distribution with alpha = roughness^2, V the height-correlated Smith visibility,
//! exactly as glsl/brdf.glsl (Fresnel excluded: the table's n and s carry it). Grid: roughness
//! r = i / (N - 1) clamped to MIN_ROUGHNESS = sqrt(1e-3) (the shader's alpha floor, so alpha >=
//! 1e-3 here too), u = sqrt(1 - cos t) = j / (N - 1) with cos t clamped to >= MIN_COS.
//!
//! Per cell: the LTC is M = R S, R a rotation about y, S = [[m11, 0, m13], [0, m22, 0],
//! [0, 0, 1]]: up to scale, every M of the form [[a, 0, b], [0, c, 0], [d, 0, e]] with positive
//! determinant. Parameters: (ln m11, ln m22, m13 / m11, phi), phi the angle of R's z axis from the
//! lobe's average direction (its normalised first moment), so that all four are scale-free and
//! near 0 for a sharp lobe. They minimise the L1 distance integral |rho / |rho| - LTC| (the
//! bound on the error of the integral over any region, such as a polygon), estimated by multiple
//! importance sampling (balance heuristic) with a fixed low-discrepancy set of 1024 samples of the
//! lobe (GGX visible normals) and 1024 of the LTC, by Nelder-Mead (restarted once at convergence).
//! (The paper's L3 distance, with R fixed to the average direction, was tried: its errors over
//! quads at grazing view were up to 4 times larger, 41% against 10%.) Order, as the paper's: from
//! the roughest row (alpha = 1, started from the clamped cosine itself) to the smoothest; the
//! normal-incidence cell of each row is the isotropic one-parameter fit (m11 = m22, m13 = phi = 0)
//! started from the row above's; each further cell starts from its neighbour at the next smaller
//! view angle. So the near-specular rows are reached gradually (the scale-free parameters keep the
//! simplex's steps meaningful as alpha falls to 1e-3), and a 40-start search from random points at
//! the worst cells found no better minimum than the chain's. The rows after the first column are
//! independent and run on rayon (RAYON_NUM_THREADS=1 for one core; the table does not depend on
//! the thread count). One core: 3 minutes.
//!
//! Also per cell, by 2^16 importance samples: n = integral of rho (directional albedo, Fresnel 1)
//! and s = integral of rho (1 - v.h)^5, and the fit's L1 error integral |rho/n - LTC| (in [0, 2]).

use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::time::Instant;

const N: usize = 64;
const MIN_ROUGHNESS: f64 = 0.031_622_776_601_683_79; // sqrt(1e-3): alpha >= 1e-3 as the shader
const MIN_COS: f64 = 1e-3;
const FIT_SAMPLES: usize = 1024; // per strategy, for the objective
const CHECK_SAMPLES: usize = 16384; // per strategy, for the reported L1 error
const MOMENT_SAMPLES: usize = 1 << 16; // n, s and the average direction

fn radical_inverse_2(mut i: u32) -> f64 {
    i = i.reverse_bits();
    i as f64 * (1.0 / 4_294_967_296.0)
}

/// Hammersley points, the first coordinate centred in its stratum.
fn hammersley(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| ((i as f64 + 0.5) / n as f64, radical_inverse_2(i as u32)))
        .collect()
}

/// The specular lobe of glsl/brdf.glsl for one roughness and view direction.
struct Lobe {
    alpha: f64,
    a2: f64,
    v: DVec3,
    nv: f64,
    g1v: f64,
}

impl Lobe {
    fn new(roughness: f64, cos_theta: f64) -> Self {
        let alpha = roughness * roughness;
        let a2 = alpha * alpha;
        let nv = cos_theta;
        let v = DVec3::new((1.0 - nv * nv).max(0.0).sqrt(), 0.0, nv);
        let g1v = 2.0 * nv / (nv + (a2 + (1.0 - a2) * nv * nv).sqrt());
        Lobe {
            alpha,
            a2,
            v,
            nv,
            g1v,
        }
    }

    fn d(&self, nh: f64) -> f64 {
        let t = nh * nh * (self.a2 - 1.0) + 1.0;
        self.a2 / (PI * t * t)
    }

    fn vis(&self, nl: f64) -> f64 {
        let (a2, nv) = (self.a2, self.nv);
        let gv = nl * (nv * nv * (1.0 - a2) + a2).sqrt();
        let gl = nv * (nl * nl * (1.0 - a2) + a2).sqrt();
        let s = gv + gl;
        if s > 0.0 {
            0.5 / s
        } else {
            0.0
        }
    }

    fn half(&self, l: DVec3) -> Option<DVec3> {
        let h = self.v + l;
        let len = h.length();
        (len > 1e-12).then(|| h / len)
    }

    /// rho(l) = D V max(n.l, 0), l unit.
    fn rho(&self, l: DVec3) -> f64 {
        if l.z <= 0.0 {
            return 0.0;
        }
        match self.half(l) {
            Some(h) if h.z > 0.0 => self.d(h.z) * self.vis(l.z) * l.z,
            _ => 0.0,
        }
    }

    /// The density of `sample` (visible normals, reflected): G1(v) D(h) / (4 n.v).
    fn pdf(&self, l: DVec3) -> f64 {
        match self.half(l) {
            Some(h) if h.z > 0.0 => self.g1v * self.d(h.z) / (4.0 * self.nv),
            _ => 0.0,
        }
    }

    /// Samples a GGX visible normal (Heitz 2018: stretch, sample the projected hemisphere,
    /// unstretch) and reflects v about it. Some directions fall below the horizon (rho = 0).
    fn sample(&self, u1: f64, u2: f64) -> DVec3 {
        let a = self.alpha;
        let vh = DVec3::new(a * self.v.x, a * self.v.y, self.v.z).normalize();
        let lensq = vh.x * vh.x + vh.y * vh.y;
        let t1 = if lensq > 0.0 {
            DVec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
        } else {
            DVec3::X
        };
        let t2 = vh.cross(t1);
        let r = u1.sqrt();
        let phi = 2.0 * PI * u2;
        let p1 = r * phi.cos();
        let mut p2 = r * phi.sin();
        let s = 0.5 * (1.0 + vh.z);
        p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        let h = DVec3::new(a * nh.x, a * nh.y, nh.z.max(1e-12)).normalize();
        2.0 * self.v.dot(h) * h - self.v
    }
}

/// An LTC: M = R S, R taking +z to `avg` (in the x-z plane),
/// S = [[m11, 0, m13], [0, m22, 0], [0, 0, 1]].
#[derive(Clone, Copy, Debug)]
struct Ltc {
    m11: f64,
    m22: f64,
    m13: f64,
    avg: DVec3,
    /// The frame's rotation from the lobe's moment direction.
    phi: f64,
}

impl Ltc {
    fn rotation(&self) -> DMat3 {
        let z = self.avg;
        DMat3::from_cols(DVec3::new(z.z, 0.0, -z.x), DVec3::Y, z)
    }

    fn m(&self) -> DMat3 {
        let s = DMat3::from_cols(
            DVec3::new(self.m11, 0.0, 0.0),
            DVec3::new(0.0, self.m22, 0.0),
            DVec3::new(self.m13, 0.0, 1.0),
        );
        self.rotation() * s
    }

    fn minv(&self) -> DMat3 {
        let s_inv = DMat3::from_cols(
            DVec3::new(1.0 / self.m11, 0.0, 0.0),
            DVec3::new(0.0, 1.0 / self.m22, 0.0),
            DVec3::new(-self.m13 / self.m11, 0.0, 1.0),
        );
        s_inv * self.rotation().transpose()
    }

    /// (ln m11) for the isotropic fit, else (ln m11, ln m22, m13 / m11, phi), phi the rotation
    /// (about y, radians) of the frame's z from the lobe's moment direction `moment`.
    fn from_params(p: &[f64], moment: DVec3) -> Self {
        if p.len() == 1 {
            let m = p[0].exp();
            return Ltc {
                m11: m,
                m22: m,
                m13: 0.0,
                avg: moment,
                phi: 0.0,
            };
        }
        let m11 = p[0].exp();
        let phi = p[3];
        let (s, c) = phi.sin_cos();
        let avg = DVec3::new(
            c * moment.x + s * moment.z,
            0.0,
            -s * moment.x + c * moment.z,
        );
        Ltc {
            m11,
            m22: p[1].exp(),
            m13: p[2] * m11,
            avg,
            phi,
        }
    }

    fn params(&self) -> [f64; 4] {
        [self.m11.ln(), self.m22.ln(), self.m13 / self.m11, self.phi]
    }
}

/// Evaluates a fixed LTC quickly: density at a direction and sampling.
struct LtcEval {
    m: DMat3,
    minv: DMat3,
    inv_det_m: f64,
}

impl LtcEval {
    fn new(ltc: &Ltc) -> Self {
        LtcEval {
            m: ltc.m(),
            minv: ltc.minv(),
            inv_det_m: 1.0 / (ltc.m11 * ltc.m22),
        }
    }

    /// D(l) = D_o(Minv l / |Minv l|) |Minv| / |Minv l|^3, D_o = max(z, 0) / pi.
    fn density(&self, l: DVec3) -> f64 {
        let w = self.minv * l;
        let len2 = w.length_squared();
        let len = len2.sqrt();
        let z = w.z / len;
        if z <= 0.0 {
            0.0
        } else {
            z / PI * self.inv_det_m / (len2 * len)
        }
    }

    /// (direction, density) for a cosine-distributed wo.
    fn sample(&self, wo: DVec3) -> (DVec3, f64) {
        let w = self.m * wo;
        let len = w.length();
        // |Minv l| = 1 / |M wo|.
        (w / len, wo.z / PI * self.inv_det_m * len * len * len)
    }
}

fn cosine_direction(u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt())
}

/// The lobe's moments by importance sampling: (integral rho, integral rho (1 - v.h)^5,
/// normalised average direction).
fn moments(lobe: &Lobe, points: &[(f64, f64)]) -> (f64, f64, DVec3) {
    let (mut n, mut s, mut dir) = (0.0, 0.0, DVec3::ZERO);
    for &(u1, u2) in points {
        let l = lobe.sample(u1, u2);
        let rho = lobe.rho(l);
        if rho <= 0.0 {
            continue;
        }
        let w = rho / lobe.pdf(l);
        let vh = lobe.half(l).map_or(0.0, |h| lobe.v.dot(h).clamp(0.0, 1.0));
        n += w;
        s += w * (1.0 - vh).powi(5);
        dir += w * l;
    }
    let k = points.len() as f64;
    dir.y = 0.0;
    (n / k, s / k, dir.normalize())
}

/// The importance-sampled distance between the normalised lobe and an LTC.
struct Objective<'a> {
    lobe: &'a Lobe,
    norm: f64,
    /// Lobe samples: (l, rho / norm, lobe pdf).
    lobe_samples: Vec<(DVec3, f64, f64)>,
    /// Cosine-distributed directions, mapped by M for the LTC's samples.
    cos_samples: Vec<DVec3>,
}

impl<'a> Objective<'a> {
    fn new(lobe: &'a Lobe, norm: f64, points: &[(f64, f64)]) -> Self {
        let lobe_samples = points
            .iter()
            .map(|&(u1, u2)| {
                let l = lobe.sample(u1, u2);
                (l, lobe.rho(l) / norm, lobe.pdf(l))
            })
            .collect();
        let cos_samples = points
            .iter()
            .map(|&(u1, u2)| cosine_direction(u1, u2))
            .collect();
        Objective {
            lobe,
            norm,
            lobe_samples,
            cos_samples,
        }
    }

    /// integral |f - g|, f the normalised lobe and g the LTC, by the balance heuristic.
    fn distance(&self, ltc: &Ltc) -> f64 {
        let e = LtcEval::new(ltc);
        let mut sum = 0.0;
        for &(l, f, pf) in &self.lobe_samples {
            let g = e.density(l);
            sum += (f - g).abs() / (pf + g);
        }
        for &wo in &self.cos_samples {
            let (l, g) = e.sample(wo);
            let f = self.lobe.rho(l) / self.norm;
            let pf = self.lobe.pdf(l);
            sum += (f - g).abs() / (pf + g);
        }
        sum / self.cos_samples.len() as f64
    }
}

/// Nelder-Mead (reflection 1, expansion 2, contraction 1/2, shrink 1/2) from x0 with an initial
/// simplex of the given steps. Stops when every vertex is within `xtol` of the best in every
/// coordinate, or after `max_evals`.
fn nelder_mead(
    f: &mut dyn FnMut(&[f64]) -> f64,
    x0: &[f64],
    step: f64,
    xtol: f64,
    max_evals: usize,
) -> (Vec<f64>, f64, usize) {
    let d = x0.len();
    let mut pts: Vec<Vec<f64>> = vec![x0.to_vec()];
    for i in 0..d {
        let mut p = x0.to_vec();
        p[i] += step;
        pts.push(p);
    }
    let mut vals: Vec<f64> = pts.iter().map(|p| f(p)).collect();
    let mut evals = d + 1;
    loop {
        let mut order: Vec<usize> = (0..=d).collect();
        order.sort_by(|&a, &b| vals[a].total_cmp(&vals[b]));
        pts = order.iter().map(|&i| pts[i].clone()).collect();
        vals = order.iter().map(|&i| vals[i]).collect();
        let size = pts[1..]
            .iter()
            .flat_map(|p| p.iter().zip(&pts[0]).map(|(a, b)| (a - b).abs()))
            .fold(0.0, f64::max);
        if size < xtol || evals >= max_evals {
            return (pts[0].clone(), vals[0], evals);
        }
        let centroid: Vec<f64> = (0..d)
            .map(|k| pts[..d].iter().map(|p| p[k]).sum::<f64>() / d as f64)
            .collect();
        let along = |t: f64| -> Vec<f64> {
            (0..d)
                .map(|k| centroid[k] + t * (pts[d][k] - centroid[k]))
                .collect()
        };
        let xr = along(-1.0);
        let fr = f(&xr);
        evals += 1;
        if fr < vals[0] {
            let xe = along(-2.0);
            let fe = f(&xe);
            evals += 1;
            if fe < fr {
                (pts[d], vals[d]) = (xe, fe);
            } else {
                (pts[d], vals[d]) = (xr, fr);
            }
            continue;
        }
        if fr < vals[d - 1] {
            (pts[d], vals[d]) = (xr, fr);
            continue;
        }
        let (xc, fc) = if fr < vals[d] {
            let xc = along(-0.5);
            let fc = f(&xc);
            (xc, fc)
        } else {
            let xc = along(0.5);
            let fc = f(&xc);
            (xc, fc)
        };
        evals += 1;
        if fc < vals[d].min(fr) {
            (pts[d], vals[d]) = (xc, fc);
            continue;
        }
        for i in 1..=d {
            let p: Vec<f64> = (0..d)
                .map(|k| pts[0][k] + 0.5 * (pts[i][k] - pts[0][k]))
                .collect();
            vals[i] = f(&p);
            pts[i] = p;
        }
        evals += d;
    }
}

#[derive(Clone, Copy, Debug)]
struct Cell {
    ltc: Ltc,
    n: f64,
    s: f64,
    l1: f64,
    evals: usize,
}

fn roughness_of(i: usize) -> f64 {
    (i as f64 / (N - 1) as f64).max(MIN_ROUGHNESS)
}

fn cos_theta_of(j: usize) -> f64 {
    let u = j as f64 / (N - 1) as f64;
    (1.0 - u * u).max(MIN_COS)
}

struct Samples {
    fit: Vec<(f64, f64)>,
    check: Vec<(f64, f64)>,
    moments: Vec<(f64, f64)>,
}

/// Fits one cell from `init` (whose shape parameters are reused in this cell's frame).
fn fit_cell(i: usize, j: usize, init: &Ltc, isotropic: bool, smp: &Samples) -> Cell {
    let lobe = Lobe::new(roughness_of(i), cos_theta_of(j));
    let (n, s, mut avg) = moments(&lobe, &smp.moments);
    if isotropic {
        avg = DVec3::Z;
    }
    let obj = Objective::new(&lobe, n, &smp.fit);
    let mut f = |p: &[f64]| obj.distance(&Ltc::from_params(p, avg));
    let x0: Vec<f64> = if isotropic {
        vec![init.m11.ln()]
    } else {
        init.params().to_vec()
    };
    let (x1, _, e1) = nelder_mead(&mut f, &x0, 0.1, 1e-6, 2000);
    // Restart once: a collapsed simplex can stop short of the minimum.
    let (x2, _, e2) = nelder_mead(&mut f, &x1, 0.02, 1e-7, 2000);
    let ltc = Ltc::from_params(&x2, avg);
    let check = Objective::new(&lobe, n, &smp.check);
    Cell {
        ltc,
        n,
        s,
        l1: check.distance(&ltc),
        evals: e1 + e2,
    }
}

fn main() {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "assets/ltc_ggx.bin".to_string());
    let smp = Samples {
        fit: hammersley(FIT_SAMPLES),
        check: hammersley(CHECK_SAMPLES),
        moments: hammersley(MOMENT_SAMPLES),
    };
    let start = Instant::now();

    // Normal incidence, roughest to smoothest: the isotropic fit, from the clamped cosine.
    let mut column = Vec::with_capacity(N);
    let mut init = Ltc {
        m11: 1.0,
        m22: 1.0,
        m13: 0.0,
        avg: DVec3::Z,
        phi: 0.0,
    };
    for i in (0..N).rev() {
        let cell = fit_cell(i, 0, &init, true, &smp);
        init = cell.ltc;
        column.push((i, cell));
    }
    column.sort_by_key(|c| c.0);

    // Each row along the view angle, from its normal-incidence cell.
    let rows: Vec<Vec<Cell>> = column
        .par_iter()
        .map(|&(i, first)| {
            let mut row = vec![first];
            for j in 1..N {
                let prev = row[j - 1].ltc;
                row.push(fit_cell(i, j, &prev, false, &smp));
            }
            eprintln!("row {i} done at {:.1} s", start.elapsed().as_secs_f64());
            row
        })
        .collect();
    let elapsed = start.elapsed().as_secs_f64();

    let mut data: Vec<f32> = Vec::with_capacity(N * N * 8);
    for row in &rows {
        for cell in row {
            // Minv normalised so that its (1, 1) entry (y) is 1.
            let minv = cell.ltc.minv();
            let k = 1.0 / minv.y_axis.y;
            let (a, b, c, d) = (
                minv.x_axis.x * k,
                minv.z_axis.x * k,
                minv.x_axis.z * k,
                minv.z_axis.z * k,
            );
            for x in [a, b, c, d, cell.n, cell.s, cell.l1, 0.0] {
                assert!(x.is_finite());
                data.push(x as f32);
            }
        }
    }
    let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(&out, bytes).expect("write the table");

    println!("row  roughness  alpha      L1 mean  L1 max (at j)  n(j=0)  evals/cell");
    for (i, row) in rows.iter().enumerate() {
        let mean = row.iter().map(|c| c.l1).sum::<f64>() / N as f64;
        let (jmax, max) = row
            .iter()
            .enumerate()
            .map(|(j, c)| (j, c.l1))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        let evals = row.iter().map(|c| c.evals).sum::<usize>() / N;
        let r = roughness_of(i);
        println!(
            "{i:3}  {r:.4}     {:.6}  {mean:.4}   {max:.4} ({jmax:2})    {:.4}  {evals}",
            r * r,
            row[0].n
        );
    }
    let all: Vec<f64> = rows.iter().flatten().map(|c| c.l1).collect();
    println!(
        "L1 over all cells: mean {:.4}, max {:.4}; {N}x{N} cells in {elapsed:.1} s on {} thread(s); wrote {out}",
        all.iter().sum::<f64>() / all.len() as f64,
        all.iter().cloned().fold(0.0, f64::max),
        rayon::current_num_threads()
    );
}
