//! A bounding volume hierarchy over world-space triangles, built with binned SAH, and the
//! ray queries the path tracer needs: closest hit and any hit, each with a filter that may
//! reject a candidate (alpha-masked texels).

use glam::Vec3;

/// A triangle as the intersector wants it: one corner and two edges.
#[derive(Clone, Copy, Debug)]
pub struct TriGeom {
    pub p0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
}

impl TriGeom {
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Self {
        TriGeom {
            p0: a,
            e1: b - a,
            e2: c - a,
        }
    }
    fn bounds(&self) -> (Vec3, Vec3) {
        let (b, c) = (self.p0 + self.e1, self.p0 + self.e2);
        (self.p0.min(b).min(c), self.p0.max(b).max(c))
    }
    pub fn area(&self) -> f32 {
        0.5 * self.e1.cross(self.e2).length()
    }

    /// Möller-Trumbore: (t, b1, b2) for t in (0, tmax), where b1, b2 weigh the 2nd and 3rd
    /// corners.
    #[inline]
    pub fn intersect(&self, o: Vec3, d: Vec3, tmax: f32) -> Option<(f32, f32, f32)> {
        let p = d.cross(self.e2);
        let det = self.e1.dot(p);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let s = o - self.p0;
        let b1 = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&b1) {
            return None;
        }
        let q = s.cross(self.e1);
        let b2 = d.dot(q) * inv;
        if b2 < 0.0 || b1 + b2 > 1.0 {
            return None;
        }
        let t = self.e2.dot(q) * inv;
        (t > 0.0 && t < tmax).then_some((t, b1, b2))
    }
}

/// A node: a leaf holds `count` triangles from `first`; an inner node (count 0) has its two
/// children at `first` and `first + 1`.
#[derive(Clone, Copy, Debug)]
struct Node {
    min: Vec3,
    max: Vec3,
    first: u32,
    count: u32,
}

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
}

#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    /// Index in the (reordered) triangle array.
    pub tri: u32,
    pub b1: f32,
    pub b2: f32,
}

const BINS: usize = 16;
const MAX_LEAF: usize = 4;
/// Cost of visiting a node relative to one triangle test.
const TRAVERSAL_COST: f32 = 1.0;

fn half_area(min: Vec3, max: Vec3) -> f32 {
    let e = (max - min).max(Vec3::ZERO);
    e.x * e.y + e.y * e.z + e.z * e.x
}

#[derive(Clone, Copy)]
struct Bin {
    min: Vec3,
    max: Vec3,
    count: usize,
}

const EMPTY_BIN: Bin = Bin {
    min: Vec3::splat(f32::INFINITY),
    max: Vec3::splat(f32::NEG_INFINITY),
    count: 0,
};

impl Bvh {
    /// Builds over `tris` and returns the order to store them in: leaf ranges index the
    /// reordered array directly. Triangles must have finite corners.
    pub fn build(tris: &[TriGeom]) -> (Bvh, Vec<u32>) {
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        if tris.is_empty() {
            return (Bvh::default(), order);
        }
        let boxes: Vec<(Vec3, Vec3)> = tris.iter().map(TriGeom::bounds).collect();
        let centroids: Vec<Vec3> = boxes.iter().map(|(a, b)| (*a + *b) * 0.5).collect();
        let mut nodes = vec![Node {
            min: Vec3::ZERO,
            max: Vec3::ZERO,
            first: 0,
            count: 0,
        }];
        // An explicit stack, so degenerate inputs cannot overflow the thread's stack.
        let mut stack = vec![(0usize, 0usize, tris.len())];
        while let Some((ni, start, end)) = stack.pop() {
            let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            let (mut cmin, mut cmax) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            for &t in &order[start..end] {
                let (a, b) = boxes[t as usize];
                min = min.min(a);
                max = max.max(b);
                cmin = cmin.min(centroids[t as usize]);
                cmax = cmax.max(centroids[t as usize]);
            }
            let count = end - start;
            nodes[ni] = Node {
                min,
                max,
                first: start as u32,
                count: count as u32,
            };
            if count <= MAX_LEAF {
                continue;
            }
            let mid = match sah_split(&order[start..end], &boxes, &centroids, cmin, cmax, min, max)
            {
                Some((axis, bin)) => {
                    let scale = BINS as f32 / (cmax[axis] - cmin[axis]);
                    let slice = &mut order[start..end];
                    let mut i = 0;
                    for j in 0..slice.len() {
                        if bin_of(centroids[slice[j] as usize][axis], cmin[axis], scale) < bin {
                            slice.swap(i, j);
                            i += 1;
                        }
                    }
                    start + i
                }
                None if count <= 16 => continue,
                // No split beats a leaf but the leaf would be large: halve by centroid.
                None => {
                    let e = cmax - cmin;
                    let axis = if e.x >= e.y && e.x >= e.z {
                        0
                    } else if e.y >= e.z {
                        1
                    } else {
                        2
                    };
                    let half = count / 2;
                    order[start..end].select_nth_unstable_by(half, |&a, &b| {
                        centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
                    });
                    start + half
                }
            };
            let mid = if mid == start || mid == end {
                start + count / 2
            } else {
                mid
            };
            let left = nodes.len();
            nodes.push(nodes[ni]);
            nodes.push(nodes[ni]);
            nodes[ni].first = left as u32;
            nodes[ni].count = 0;
            stack.push((left, start, mid));
            stack.push((left + 1, mid, end));
        }
        (Bvh { nodes }, order)
    }

    /// The closest hit in (0, tmax) that `accept` agrees to (it sees the triangle and
    /// barycentrics of each candidate closer than the best so far).
    pub fn closest(
        &self,
        tris: &[TriGeom],
        o: Vec3,
        d: Vec3,
        tmax: f32,
        mut accept: impl FnMut(u32, f32, f32) -> bool,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut tmax = tmax;
        self.traverse(o, d, &mut tmax, |first, count, tmax| {
            for i in first..first + count {
                if let Some((t, b1, b2)) = tris[i as usize].intersect(o, d, *tmax) {
                    if accept(i, b1, b2) {
                        *tmax = t;
                        best = Some(Hit { t, tri: i, b1, b2 });
                    }
                }
            }
            false
        });
        best
    }

    /// Whether anything that `accept` agrees to lies in (0, tmax).
    pub fn any(
        &self,
        tris: &[TriGeom],
        o: Vec3,
        d: Vec3,
        tmax: f32,
        mut accept: impl FnMut(u32, f32, f32) -> bool,
    ) -> bool {
        let mut found = false;
        let mut tmax = tmax;
        self.traverse(o, d, &mut tmax, |first, count, tmax| {
            for i in first..first + count {
                if let Some((_, b1, b2)) = tris[i as usize].intersect(o, d, *tmax) {
                    if accept(i, b1, b2) {
                        found = true;
                        return true;
                    }
                }
            }
            false
        });
        found
    }

    /// Visits leaves the ray may hit, nearer child first; `leaf` returns true to stop.
    fn traverse(
        &self,
        o: Vec3,
        d: Vec3,
        tmax: &mut f32,
        mut leaf: impl FnMut(u32, u32, &mut f32) -> bool,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inv = d.recip();
        let mut stack = [0u32; 96];
        let mut sp = 0usize;
        let mut ni = 0u32;
        if slab(&self.nodes[0], o, inv, *tmax).is_none() {
            return;
        }
        loop {
            let n = &self.nodes[ni as usize];
            if n.count > 0 {
                if leaf(n.first, n.count, tmax) {
                    return;
                }
            } else {
                let (a, b) = (n.first, n.first + 1);
                let ta = slab(&self.nodes[a as usize], o, inv, *tmax);
                let tb = slab(&self.nodes[b as usize], o, inv, *tmax);
                match (ta, tb) {
                    (Some(ta), Some(tb)) => {
                        let (near, far) = if ta <= tb { (a, b) } else { (b, a) };
                        if sp < stack.len() {
                            stack[sp] = far;
                            sp += 1;
                            ni = near;
                            continue;
                        }
                        // The stack is full (only a pathological tree gets here): take the
                        // far child later by walking both in turn.
                        self.traverse_from(far, o, d, tmax, &mut leaf);
                        ni = near;
                        continue;
                    }
                    (Some(_), None) => {
                        ni = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        ni = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next subtree still in reach.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let cand = stack[sp];
                if slab(&self.nodes[cand as usize], o, inv, *tmax).is_some() {
                    ni = cand;
                    break;
                }
            }
        }
    }

    fn traverse_from(
        &self,
        root: u32,
        o: Vec3,
        d: Vec3,
        tmax: &mut f32,
        leaf: &mut impl FnMut(u32, u32, &mut f32) -> bool,
    ) {
        // Recursive fallback for a full stack: rare, and bounded by the tree's depth.
        let inv = d.recip();
        let n = self.nodes[root as usize];
        if slab(&n, o, inv, *tmax).is_none() {
            return;
        }
        if n.count > 0 {
            leaf(n.first, n.count, tmax);
        } else {
            self.traverse_from(n.first, o, d, tmax, leaf);
            self.traverse_from(n.first + 1, o, d, tmax, leaf);
        }
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }
}

fn bin_of(c: f32, cmin: f32, scale: f32) -> usize {
    (((c - cmin) * scale) as usize).min(BINS - 1)
}

/// The cheapest binned SAH split (axis, first bin of the right side), if it beats a leaf.
fn sah_split(
    order: &[u32],
    boxes: &[(Vec3, Vec3)],
    centroids: &[Vec3],
    cmin: Vec3,
    cmax: Vec3,
    min: Vec3,
    max: Vec3,
) -> Option<(usize, usize)> {
    let leaf_cost = order.len() as f32;
    let parent_area = half_area(min, max);
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        let extent = cmax[axis] - cmin[axis];
        if extent.is_nan() || extent <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent;
        let mut bins = [EMPTY_BIN; BINS];
        for &t in order {
            let b = &mut bins[bin_of(centroids[t as usize][axis], cmin[axis], scale)];
            let (lo, hi) = boxes[t as usize];
            b.min = b.min.min(lo);
            b.max = b.max.max(hi);
            b.count += 1;
        }
        // Right-to-left sweep stores the cost of each right side; left-to-right adds the left.
        let mut right_cost = [0.0f32; BINS];
        let mut acc = EMPTY_BIN;
        for i in (1..BINS).rev() {
            acc.min = acc.min.min(bins[i].min);
            acc.max = acc.max.max(bins[i].max);
            acc.count += bins[i].count;
            right_cost[i] = if acc.count > 0 {
                acc.count as f32 * half_area(acc.min, acc.max)
            } else {
                0.0
            };
        }
        let mut acc = EMPTY_BIN;
        for i in 1..BINS {
            let b = bins[i - 1];
            acc.min = acc.min.min(b.min);
            acc.max = acc.max.max(b.max);
            acc.count += b.count;
            if acc.count == 0 || acc.count == order.len() {
                continue;
            }
            let cost = acc.count as f32 * half_area(acc.min, acc.max) + right_cost[i];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, i));
            }
        }
    }
    let (cost, axis, bin) = best?;
    let split_cost = TRAVERSAL_COST + cost / parent_area.max(f32::MIN_POSITIVE);
    (split_cost < leaf_cost || order.len() > 16).then_some((axis, bin))
}

/// Entry distance of the ray into a node's box, if it enters before `tmax`.
#[inline]
fn slab(n: &Node, o: Vec3, inv: Vec3, tmax: f32) -> Option<f32> {
    let t0 = (n.min - o) * inv;
    let t1 = (n.max - o) * inv;
    // f32::min/max drop a NaN operand (0 x inf on a box face), which keeps the test correct.
    let tnear = t0.min(t1).max_element().max(0.0);
    let tfar = t0.max(t1).min_element().min(tmax);
    (tnear <= tfar).then_some(tnear)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::sampling::Pcg32;

    fn random_tris(n: usize) -> Vec<TriGeom> {
        let mut rng = Pcg32::new(9, 9);
        let mut r3 = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        (0..n)
            .map(|_| {
                let c = r3() * 10.0;
                TriGeom::new(c, c + r3() - 0.5, c + r3() - 0.5)
            })
            .collect()
    }

    #[test]
    fn agrees_with_brute_force() {
        let tris = random_tris(3000);
        let (bvh, order) = Bvh::build(&tris);
        let sorted: Vec<TriGeom> = order.iter().map(|&i| tris[i as usize]).collect();
        let mut rng = Pcg32::new(4, 4);
        let mut hits = 0;
        for _ in 0..2000 {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 12.0 - 1.0;
            let d = (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5).normalize();
            let brute = sorted
                .iter()
                .enumerate()
                .filter_map(|(i, t)| t.intersect(o, d, f32::INFINITY).map(|h| (h.0, i)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let h = bvh.closest(&sorted, o, d, f32::INFINITY, |_, _, _| true);
            assert_eq!(brute.map(|b| b.1 as u32), h.map(|h| h.tri));
            assert_eq!(
                h.is_some(),
                bvh.any(&sorted, o, d, f32::INFINITY, |_, _, _| true)
            );
            hits += h.is_some() as usize;
        }
        assert!(hits > 200, "{hits}");
    }

    #[test]
    fn filter_skips_rejected_hits() {
        let tris = vec![
            TriGeom::new(
                Vec3::new(-1.0, -1.0, -1.0),
                Vec3::new(1.0, -1.0, -1.0),
                Vec3::new(0.0, 1.0, -1.0),
            ),
            TriGeom::new(
                Vec3::new(-1.0, -1.0, -2.0),
                Vec3::new(1.0, -1.0, -2.0),
                Vec3::new(0.0, 1.0, -2.0),
            ),
        ];
        let (bvh, order) = Bvh::build(&tris);
        let sorted: Vec<TriGeom> = order.iter().map(|&i| tris[i as usize]).collect();
        let near = order.iter().position(|&i| i == 0).unwrap() as u32;
        let h = bvh
            .closest(&sorted, Vec3::ZERO, Vec3::NEG_Z, 10.0, |t, _, _| t != near)
            .unwrap();
        assert!((h.t - 2.0).abs() < 1e-6);
        assert!(!bvh.any(&sorted, Vec3::ZERO, Vec3::NEG_Z, 10.0, |_, _, _| false));
        assert!(bvh
            .closest(&sorted, Vec3::ZERO, Vec3::NEG_Z, 1.5, |t, _, _| t != near)
            .is_none());
    }
}
