//! Two corpus runs side by side (their results.json): what a change did per class and which
//! scenes it moved, as the closing notes report it (before -> after).

use super::run::{ClassSummary, Report, SceneResult};
use std::fmt::Write;

/// A scene counts as better or worse when its relMSE moved by more than this by default: below
/// the references' noise target (0.002), so that the list shows every scene worth a look.
pub const MOVED: f64 = 0.001;

/// How the scenes both runs hold moved, by relMSE.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Moves {
    pub better: usize,
    pub worse: usize,
    /// (after - before, name), the most improved first.
    pub moved: Vec<(f64, String)>,
}

/// The scenes of `class` (None: all) in both runs, and those that moved by more than `moved`.
pub fn moves(before: &Report, after: &Report, class: Option<&str>, moved: f64) -> Moves {
    let mut m = Moves::default();
    for a in after
        .scenes
        .iter()
        .filter(|s| class.is_none_or(|c| s.class == c))
    {
        let Some(b) = scene(before, &a.name) else {
            continue;
        };
        let d = a.rel_mse - b.rel_mse;
        if d.abs() > moved {
            if d < 0.0 {
                m.better += 1;
            } else {
                m.worse += 1;
            }
            m.moved.push((d, a.name.clone()));
        }
    }
    m.moved.sort_by(|x, y| x.0.total_cmp(&y.0));
    m
}

fn scene<'a>(report: &'a Report, name: &str) -> Option<&'a SceneResult> {
    report.scenes.iter().find(|s| s.name == name)
}

/// "a -> b", or "a" when both print the same.
fn arrow(a: f64, b: f64, digits: usize) -> String {
    let (x, y) = (format!("{a:.digits$}"), format!("{b:.digits$}"));
    if x == y {
        x
    } else {
        format!("{x} -> {y}")
    }
}

/// The Markdown of the comparison: a row per class both runs hold (and all), then the scenes
/// that moved, and the scenes only one run holds.
pub fn markdown(before: &Report, after: &Report, moved: f64) -> String {
    let mut s = String::from(
        "| class | scenes | relMSE median | p90 | worst | FLIP median | p90 | mean off by, p90 | better | worse |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    let rows = after
        .classes
        .iter()
        .filter_map(|a| {
            let b = before.classes.iter().find(|b| b.class == a.class)?;
            Some((b, a, Some(a.class.as_str())))
        })
        .chain(std::iter::once((&before.all, &after.all, None)));
    for (b, a, class) in rows {
        row(&mut s, b, a, &moves(before, after, class, moved));
    }
    let all = moves(before, after, None, moved);
    if !all.moved.is_empty() {
        let _ = write!(
            s,
            "\nMoved by more than {moved} (relMSE, FLIP, image mean over the reference's):\n\n"
        );
        for (_, name) in &all.moved {
            let (b, a) = (scene(before, name).unwrap(), scene(after, name).unwrap());
            let _ = writeln!(
                s,
                "- {name}: {}, {}, {}",
                arrow(b.rel_mse, a.rel_mse, 4),
                arrow(b.flip, a.flip, 3),
                arrow(b.mean_ratio, a.mean_ratio, 2)
            );
        }
    }
    for (report, other, which) in [(before, after, "before"), (after, before, "after")] {
        let only: Vec<&str> = report
            .scenes
            .iter()
            .filter(|x| scene(other, &x.name).is_none())
            .map(|x| x.name.as_str())
            .collect();
        if !only.is_empty() {
            let _ = writeln!(s, "\nOnly {which}: {}", only.join(", "));
        }
    }
    s
}

fn row(s: &mut String, b: &ClassSummary, a: &ClassSummary, m: &Moves) {
    let _ = writeln!(
        s,
        "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
        a.class,
        a.scenes,
        arrow(b.rel_mse.median, a.rel_mse.median, 4),
        arrow(b.rel_mse.p90, a.rel_mse.p90, 4),
        arrow(b.rel_mse.worst, a.rel_mse.worst, 4),
        arrow(b.flip.median, a.flip.median, 3),
        arrow(b.flip.p90, a.flip.p90, 3),
        arrow(b.mean_error.p90, a.mean_error.p90, 3),
        m.better,
        m.worse,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::corpus::run::tests::{report_of, scene_result};

    #[test]
    fn the_scenes_that_moved_are_counted_and_listed_best_first() {
        let before = report_of(vec![
            scene_result("openings-001", "openings", 0.050),
            scene_result("openings-003", "openings", 0.020),
            scene_result("emitters-001", "emitters", 0.010),
            scene_result("emitters-003", "emitters", 0.030),
        ]);
        let after = report_of(vec![
            scene_result("openings-001", "openings", 0.030),
            scene_result("openings-003", "openings", 0.0205),
            scene_result("emitters-001", "emitters", 0.015),
            scene_result("scale-001", "scale", 0.010),
        ]);
        let m = moves(&before, &after, None, MOVED);
        assert_eq!((m.better, m.worse), (1, 1));
        let names: Vec<&str> = m.moved.iter().map(|(_, n)| n.as_str()).collect();
        assert_eq!(names, ["openings-001", "emitters-001"]);
        let openings = moves(&before, &after, Some("openings"), MOVED);
        assert_eq!((openings.better, openings.worse), (1, 0));

        let md = markdown(&before, &after, MOVED);
        assert!(md.contains("- openings-001: 0.0500 -> 0.0300"), "{md}");
        assert!(!md.contains("openings-003:"), "{md}");
        assert!(md.contains("Only before: emitters-003"), "{md}");
        assert!(md.contains("Only after: scale-001"), "{md}");
        // A row per class both hold, and all.
        assert_eq!(
            md.lines().filter(|l| l.starts_with("| ")).count(),
            1 + 2 + 1,
            "{md}"
        );
    }
}
