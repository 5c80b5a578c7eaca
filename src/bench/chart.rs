//! The Pareto chart: error (relMSE) against frame time, both on log axes, drawn straight into
//! an RGB image (no plotting or font dependency; see `font`).

use super::font;
use image::{Rgb, RgbImage};

/// One setting on the chart.
#[derive(Clone, Debug)]
pub struct Point {
    /// Shown beside the point (the row number in results.md).
    pub index: usize,
    pub label: String,
    /// Milliseconds (x).
    pub time: f64,
    /// relMSE (y).
    pub error: f64,
    pub paper: bool,
    pub pareto: bool,
}

const W: u32 = 960;
const H: u32 = 640;
const LEFT: i32 = 100;
const RIGHT: i32 = W as i32 - 40;
const TOP: i32 = 70;
const BOTTOM: i32 = H as i32 - 80;

const WHITE: Rgb<u8> = Rgb([255, 255, 255]);
const BLACK: Rgb<u8> = Rgb([0, 0, 0]);
const GRID: Rgb<u8> = Rgb([225, 225, 225]);
const GREY: Rgb<u8> = Rgb([110, 110, 110]);
const BLUE: Rgb<u8> = Rgb([40, 90, 200]);
const ORANGE: Rgb<u8> = Rgb([230, 120, 20]);
const RED: Rgb<u8> = Rgb([200, 30, 40]);

struct Canvas(RgbImage);

impl Canvas {
    fn put(&mut self, x: i32, y: i32, c: Rgb<u8>) {
        if x >= 0 && y >= 0 && (x as u32) < W && (y as u32) < H {
            self.0.put_pixel(x as u32, y as u32, c);
        }
    }
    fn rect(&mut self, x0: i32, y0: i32, x1: i32, y1: i32, c: Rgb<u8>) {
        for y in y0..=y1 {
            for x in x0..=x1 {
                self.put(x, y, c);
            }
        }
    }
    /// Bresenham with a square brush of `width` pixels.
    fn line(&mut self, (x0, y0): (i32, i32), (x1, y1): (i32, i32), c: Rgb<u8>, width: i32) {
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
        let (mut x, mut y, mut err) = (x0, y0, dx + dy);
        let lo = -(width - 1) / 2;
        loop {
            self.rect(x + lo, y + lo, x + lo + width - 1, y + lo + width - 1, c);
            if x == x1 && y == y1 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
        }
    }
    fn disc(&mut self, cx: i32, cy: i32, r: i32, c: Rgb<u8>) {
        for y in -r..=r {
            for x in -r..=r {
                if x * x + y * y <= r * r + r {
                    self.put(cx + x, cy + y, c);
                }
            }
        }
    }
    fn diamond(&mut self, cx: i32, cy: i32, r: i32, c: Rgb<u8>) {
        for y in -r..=r {
            for x in -r..=r {
                if x.abs() + y.abs() <= r {
                    self.put(cx + x, cy + y, c);
                }
            }
        }
    }
    fn text(&mut self, x: i32, y: i32, s: &str, scale: i32, c: Rgb<u8>) {
        for (i, ch) in s.chars().enumerate() {
            let ox = x + i as i32 * font::ADVANCE as i32 * scale;
            for (row, bits) in font::glyph(ch).iter().enumerate() {
                for col in 0..font::WIDTH as i32 {
                    if bits & (1 << (4 - col)) != 0 {
                        let (px, py) = (ox + col * scale, y + row as i32 * scale);
                        self.rect(px, py, px + scale - 1, py + scale - 1, c);
                    }
                }
            }
        }
    }
}

/// x0, y0, x1, y1 (inclusive).
type Rect = (i32, i32, i32, i32);

/// Overlapping area of two rectangles, in pixels.
fn overlap(a: &Rect, b: &Rect) -> i32 {
    let w = (a.2.min(b.2) - a.0.max(b.0) + 1).max(0);
    let h = (a.3.min(b.3) - a.1.max(b.1) + 1).max(0);
    w * h
}

fn text_width(s: &str, scale: i32) -> i32 {
    (s.chars().count() as i32 * font::ADVANCE as i32 - 1).max(0) * scale
}

/// log10 range over the values, padded a little so points do not sit on the frame.
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v.log10());
        hi = hi.max(v.log10());
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(0.05);
    (lo - pad, hi + pad)
}

/// Ticks on a log axis: decades when they give at least three, else 1-2-5, else 1 to 9.
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    for mults in [
        &[1.0][..],
        &[1.0, 2.0, 5.0],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
    ] {
        let mut ticks = Vec::new();
        for e in (lo.floor() as i32)..=(hi.ceil() as i32) {
            for m in mults {
                let v = m * 10f64.powi(e);
                let l = v.log10();
                if l >= lo && l <= hi {
                    ticks.push(v);
                }
            }
        }
        if ticks.len() >= 3 || mults.len() == 9 {
            return ticks;
        }
    }
    Vec::new()
}

/// A tick label: plain decimals in a readable range, else `2e-5`.
pub fn tick_label(v: f64) -> String {
    if (1e-3..1e5).contains(&v) {
        let digits = (-v.log10().floor()).max(0.0) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:e}")
    }
}

/// Draws the chart; `title` goes at the top. Points with a non-positive or non-finite
/// coordinate cannot sit on a log axis and are left out.
pub fn draw(points: &[Point], title: &str) -> RgbImage {
    let mut c = Canvas(RgbImage::from_pixel(W, H, WHITE));
    let shown: Vec<&Point> = points
        .iter()
        .filter(|p| p.time.is_finite() && p.time > 0.0 && p.error.is_finite() && p.error > 0.0)
        .collect();
    let (x_lo, x_hi) = log_range(shown.iter().map(|p| p.time));
    let (y_lo, y_hi) = log_range(shown.iter().map(|p| p.error));
    let px = |t: f64| LEFT + ((t.log10() - x_lo) / (x_hi - x_lo) * (RIGHT - LEFT) as f64) as i32;
    let py = |e: f64| BOTTOM - ((e.log10() - y_lo) / (y_hi - y_lo) * (BOTTOM - TOP) as f64) as i32;

    for t in log_ticks(x_lo, x_hi) {
        let x = px(t);
        c.line((x, TOP), (x, BOTTOM), GRID, 1);
        c.line((x, BOTTOM), (x, BOTTOM + 6), BLACK, 1);
        let s = tick_label(t);
        c.text(x - text_width(&s, 2) / 2, BOTTOM + 12, &s, 2, BLACK);
    }
    for e in log_ticks(y_lo, y_hi) {
        let y = py(e);
        c.line((LEFT, y), (RIGHT, y), GRID, 1);
        c.line((LEFT - 6, y), (LEFT, y), BLACK, 1);
        let s = tick_label(e);
        c.text(LEFT - 10 - text_width(&s, 2), y - 7, &s, 2, BLACK);
    }
    c.line((LEFT, TOP), (LEFT, BOTTOM), BLACK, 2);
    c.line((LEFT, BOTTOM), (RIGHT, BOTTOM), BLACK, 2);
    let xt = "still frame wall time, ms (log)";
    c.text(
        (LEFT + RIGHT - text_width(xt, 2)) / 2,
        H as i32 - 36,
        xt,
        2,
        BLACK,
    );
    c.text(LEFT - 90, TOP - 26, "relMSE (log)", 2, BLACK);
    c.text(LEFT, 14, title, 2, BLACK);

    // Legend, top right.
    let lx = RIGHT - 330;
    c.disc(lx, 44, 5, BLUE);
    c.text(lx + 10, 38, "voxgi", 2, BLACK);
    c.diamond(lx + 90, 44, 7, ORANGE);
    c.text(lx + 102, 38, "paper", 2, BLACK);
    c.line((lx + 180, 44), (lx + 204, 44), RED, 3);
    c.text(lx + 210, 38, "pareto", 2, BLACK);

    let mut front: Vec<&&Point> = shown.iter().filter(|p| p.pareto).collect();
    front.sort_by(|a, b| a.time.total_cmp(&b.time));
    for w in front.windows(2) {
        let (a, b) = (w[0], w[1]);
        c.line((px(a.time), py(a.error)), (px(b.time), py(b.error)), RED, 3);
    }
    for p in &shown {
        let (x, y) = (px(p.time), py(p.error));
        if p.pareto {
            c.disc(x, y, 9, RED);
        }
        if p.paper {
            c.diamond(x, y, 7, ORANGE);
        } else {
            c.disc(x, y, 5, BLUE);
        }
    }
    // Labels last, so that no point covers them: the front's (with their settings) placed
    // first, each where it overlaps the points and earlier labels least.
    let mut taken: Vec<Rect> = shown
        .iter()
        .map(|p| {
            let (x, y) = (px(p.time), py(p.error));
            (x - 9, y - 9, x + 9, y + 9)
        })
        .collect();
    let mut order: Vec<&&Point> = shown.iter().collect();
    order.sort_by_key(|p| !p.pareto);
    for p in order {
        let (x, y) = (px(p.time), py(p.error));
        let (s, colour) = if p.pareto {
            (format!("{} {}", p.index, p.label), RED)
        } else {
            (p.index.to_string(), GREY)
        };
        let (w, h) = (text_width(&s, 2), 14);
        let candidates = [
            (x + 12, y - 16),
            (x + 12, y + 3),
            (x - 12 - w, y - 16),
            (x - 12 - w, y + 3),
            (x - w / 2, y - 28),
            (x - w / 2, y + 13),
        ];
        let cost = |&(tx, ty): &(i32, i32)| {
            let r = (tx, ty, tx + w, ty + h);
            let outside = r.0 < 0 || r.1 < 0 || r.2 >= W as i32 || r.3 >= H as i32;
            let overlap: i32 = taken.iter().map(|t| overlap(&r, t)).sum();
            overlap + if outside { 1 << 20 } else { 0 }
        };
        // min_by_key keeps the first of equal costs: the preferred places come first.
        let &(tx, ty) = candidates
            .iter()
            .min_by_key(|c| cost(c))
            .unwrap_or(&candidates[0]);
        taken.push((tx, ty, tx + w, ty + h));
        // A white halo keeps the text readable over grid lines and the front.
        for (dx, dy) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
            c.text(tx + dx, ty + dy, &s, 2, WHITE);
        }
        c.text(tx, ty, &s, 2, colour);
    }
    c.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_and_labels() {
        assert_eq!(log_ticks(-3.2, 0.1), vec![1e-3, 1e-2, 1e-1, 1.0]);
        assert_eq!(log_ticks(0.9, 1.8), vec![10.0, 20.0, 50.0]);
        assert_eq!(tick_label(20.0), "20");
        assert_eq!(tick_label(0.05), "0.05");
        assert_eq!(tick_label(0.002), "0.002");
        assert_eq!(tick_label(2e-5), "2e-5");
    }

    #[test]
    fn draws_points_and_front() {
        let p = |index, time, error, paper, pareto| Point {
            index,
            label: format!("s{index}"),
            time,
            error,
            paper,
            pareto,
        };
        let img = draw(
            &[
                p(1, 10.0, 0.5, false, true),
                p(2, 20.0, 0.1, true, true),
                p(3, 30.0, 0.3, false, false),
                p(4, f64::NAN, 0.3, false, false),
            ],
            "test",
        );
        assert_eq!(img.dimensions(), (W, H));
        let count = |c: Rgb<u8>| img.pixels().filter(|p| **p == c).count();
        assert!(count(RED) > 100 && count(ORANGE) > 50 && count(BLUE) > 50);
    }
}
