//! The Pareto front of settings that trade time against error (both to be minimised).

/// For each point (time, error): whether no other point is at least as good in both and
/// strictly better in one. Equal points do not beat each other, so all of them stay on the
/// front. Points with a NaN or infinite coordinate are never on it and beat nothing.
pub fn front(points: &[(f64, f64)]) -> Vec<bool> {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    points
        .iter()
        .map(|p| {
            finite(p)
                && !points
                    .iter()
                    .any(|q| finite(q) && q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::front;

    #[test]
    fn single_point_is_the_front() {
        assert_eq!(front(&[(3.0, 0.5)]), vec![true]);
        assert_eq!(front(&[]), Vec::<bool>::new());
    }

    #[test]
    fn dominated_points_are_excluded() {
        let p = [
            (1.0, 0.9), // fastest
            (2.0, 0.5),
            (3.0, 0.6), // slower and worse than (2, 0.5)
            (4.0, 0.1), // most accurate
            (5.0, 0.1), // as accurate as (4, 0.1) but slower
            (2.5, 0.5), // as accurate as (2, 0.5) but slower
        ];
        assert_eq!(front(&p), vec![true, true, false, true, false, false]);
    }

    #[test]
    fn ties_stay_on_the_front() {
        // Two identical points do not beat each other; a third equal in time but worse does
        // not make it.
        let p = [(2.0, 0.3), (2.0, 0.3), (2.0, 0.4), (1.0, 0.5)];
        assert_eq!(front(&p), vec![true, true, false, true]);
    }

    #[test]
    fn non_finite_points_are_left_out() {
        let p = [
            (1.0, f64::NAN),
            (2.0, 0.5),
            (f64::INFINITY, 0.0),
            (0.5, 1.0),
        ];
        assert_eq!(front(&p), vec![false, true, false, true]);
    }
}
