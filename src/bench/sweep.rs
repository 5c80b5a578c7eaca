//! The settings a benchmark runs: presets and a small language of axes.
//!
//! ```text
//! SPEC   := PART ('|' PART)*         the union of the parts, duplicates dropped
//! PART   := PRESET | AXIS (';' AXIS)*
//! PRESET := default | tiny
//! AXIS   := NAME '=' VALUE (',' VALUE)*
//! ```
//!
//! A list of axes is the cartesian product of their values over the defaults (the first axis
//! varies slowest). `paper=1` starts from the paper's settings at the given voxel resolution,
//! and the other axes are applied on top of that.

use crate::gi::{GiSettings, FIELDS};

/// One setting of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Setting {
    /// What sets it apart from the defaults at its resolution, e.g. `64^3 paper cones=4`.
    pub label: String,
    pub gi: GiSettings,
}

impl Setting {
    pub fn new(gi: GiSettings) -> Setting {
        Setting {
            label: label(&gi),
            gi,
        }
    }
}

/// The settings `gi` starts from: the project's defaults or the paper's, at its resolution.
fn base_of(gi: &GiSettings) -> GiSettings {
    if gi.paper {
        GiSettings::paper(gi.voxels)
    } else {
        GiSettings {
            voxels: gi.voxels,
            ..GiSettings::default()
        }
    }
}

/// `64^3`, then `paper`, then every field that differs from its base.
pub fn label(gi: &GiSettings) -> String {
    let b = base_of(gi);
    let mut s = format!("{}^3", gi.voxels);
    if gi.paper {
        s.push_str(" paper");
    }
    for f in FIELDS
        .iter()
        .filter(|f| !matches!(f.axis, "voxels" | "paper"))
    {
        let (v, base) = ((f.get)(gi), (f.get)(&b));
        if v != base {
            s.push_str(&format!(" {}={}", f.axis, v.label()));
        }
    }
    s
}

/// Parses a sweep: a preset name, a list of axes, or a union of them (see [`SWEEP_HELP`]).
pub fn parse(spec: &str) -> Result<Vec<Setting>, String> {
    let mut out: Vec<Setting> = Vec::new();
    for part in spec.split('|') {
        let part = part.trim();
        let settings = match part {
            "default" => default_preset(),
            "tiny" => vec![
                GiSettings {
                    voxels: 32,
                    ..GiSettings::default()
                },
                GiSettings::paper(32),
            ],
            "" => return Err("empty sweep".into()),
            axes => product(axes)?,
        };
        for gi in settings {
            if !out.iter().any(|s| s.gi == gi) {
                out.push(Setting::new(gi));
            }
        }
    }
    Ok(out)
}

/// One axis at a time around the defaults, and the paper's settings at every resolution.
fn default_preset() -> Vec<GiSettings> {
    let d = GiSettings::default();
    let mut v = Vec::new();
    for voxels in [32, 64, 128, 256] {
        v.push(GiSettings {
            voxels,
            ..d.clone()
        });
        v.push(GiSettings::paper(voxels));
    }
    for cone_count in [1, 4, 6, 9, 16] {
        v.push(GiSettings {
            cone_count,
            ..d.clone()
        });
    }
    for cone_aperture_deg in [30.0, 36.0, 45.0, 60.0, 90.0] {
        v.push(GiSettings {
            cone_aperture_deg,
            ..d.clone()
        });
    }
    for step_factor in [0.25, 0.5, 1.0] {
        v.push(GiSettings {
            step_factor,
            ..d.clone()
        });
    }
    for bounces in [1, 2] {
        v.push(GiSettings {
            bounces,
            ..d.clone()
        });
    }
    v
}

fn parse_value(axis: &str, text: &str, min: f64, max: f64, integer: bool) -> Result<f64, String> {
    let t = text.trim();
    let v = match t {
        "true" | "on" | "yes" if max == 1.0 && integer => 1.0,
        "false" | "off" | "no" if max == 1.0 && integer => 0.0,
        _ => t
            .parse::<f64>()
            .map_err(|_| format!("{axis}: {t:?} is not a number"))?,
    };
    if !v.is_finite() || v < min || v > max {
        return Err(format!("{axis}: {t} is out of range ({min} to {max})"));
    }
    if integer && v.fract() != 0.0 {
        return Err(format!("{axis}: {t} is not a whole number"));
    }
    Ok(v)
}

/// `name=a,b;name=c`: the cartesian product over the defaults.
fn product(spec: &str) -> Result<Vec<GiSettings>, String> {
    let mut axes: Vec<(usize, Vec<f64>)> = Vec::new();
    for item in spec.split(';').map(str::trim).filter(|s| !s.is_empty()) {
        let (name, values) = item
            .split_once('=')
            .ok_or_else(|| format!("{item:?}: expected NAME=VALUES or a preset (default, tiny)"))?;
        let name = name.trim();
        let index = FIELDS.iter().position(|f| f.axis == name).ok_or_else(|| {
            let names: Vec<&str> = FIELDS.iter().map(|f| f.axis).collect();
            format!("unknown axis {name:?} (the axes are: {})", names.join(", "))
        })?;
        if axes.iter().any(|(i, _)| *i == index) {
            return Err(format!("axis {name} is given twice"));
        }
        let f = &FIELDS[index];
        let integer = (f.get)(&GiSettings::default()).integer();
        let values = values
            .split(',')
            .map(|v| parse_value(name, v, f.min, f.max, integer))
            .collect::<Result<Vec<_>, _>>()?;
        axes.push((index, values));
    }
    if axes.is_empty() {
        return Err("no axes".into());
    }
    let count: usize = axes.iter().map(|(_, v)| v.len()).product();
    if count > 1000 {
        return Err(format!("{count} settings is too many"));
    }
    let mut out = Vec::with_capacity(count);
    for n in 0..count {
        // Mixed-radix digits of n, the last axis fastest.
        let mut rest = n;
        let mut chosen = vec![0.0; axes.len()];
        for (k, (_, values)) in axes.iter().enumerate().rev() {
            chosen[k] = values[rest % values.len()];
            rest /= values.len();
        }
        // Voxels and paper are read first: they pick the base the others apply to.
        let value_of = |axis: &str| {
            axes.iter()
                .zip(&chosen)
                .find(|((i, _), _)| FIELDS[*i].axis == axis)
                .map(|(_, v)| *v)
        };
        let voxels = value_of("voxels").map_or(GiSettings::default().voxels, |v| v as u32);
        let mut gi = if value_of("paper").is_some_and(|v| v != 0.0) {
            GiSettings::paper(voxels)
        } else {
            GiSettings {
                voxels,
                ..GiSettings::default()
            }
        };
        for ((index, _), v) in axes.iter().zip(&chosen) {
            let f = &FIELDS[*index];
            if !matches!(f.axis, "voxels" | "paper") {
                (f.set)(&mut gi, *v);
            }
        }
        out.push(gi);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets() {
        let tiny = parse("tiny").unwrap();
        assert_eq!(tiny.len(), 2);
        assert_eq!(tiny[0].label, "32^3");
        assert_eq!(tiny[1].label, "32^3 paper");
        assert!(tiny.iter().all(|s| s.gi.voxels == 32));
        let d = parse("default").unwrap();
        // 4 resolutions x (default, paper), then each axis without the default it repeats.
        assert_eq!(d.len(), 8 + 4 + 4 + 2 + 1);
        let labels: Vec<&str> = d.iter().map(|s| s.label.as_str()).collect();
        for l in [
            "256^3 paper",
            "64^3 cones=1",
            "64^3 aperture=30",
            "64^3 step=0.25",
            "64^3 bounces=1",
        ] {
            assert!(labels.contains(&l), "{l} missing from {labels:?}");
        }
    }

    #[test]
    fn product_over_the_defaults() {
        let s = parse("voxels=32,64;cones=4,6;paper=0,1").unwrap();
        assert_eq!(s.len(), 8);
        assert_eq!(s[0].label, "32^3 cones=4");
        assert_eq!(s[1].label, "32^3 paper cones=4");
        assert_eq!(s[7].label, "64^3 paper");
        assert_eq!(s[7].gi, GiSettings::paper(64));
        assert_eq!(s[2].gi.cone_count, 6);
        assert_eq!(s[2].gi.start_offset, GiSettings::default().start_offset);
        let s = parse("step=0.25;voxel-shadows=on").unwrap();
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].gi.voxels, GiSettings::default().voxels);
        assert_eq!(s[0].label, "64^3 step=0.25 voxel-shadows=1");
        let s = parse("area-lights=0,1").unwrap();
        let labels: Vec<&str> = s.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(labels, ["64^3 area-lights=0", "64^3"]);
        assert!(!s[0].gi.area_lights && s[1].gi.area_lights);
    }

    #[test]
    fn union_drops_duplicates() {
        let s = parse("tiny | voxels=32;paper=0,1 | voxels=64").unwrap();
        assert_eq!(s.len(), 3);
        assert_eq!(s[2].label, "64^3");
    }

    #[test]
    fn bad_specs_are_errors() {
        for bad in [
            "",
            "fast",
            "voxels=2",
            "voxels=32.5",
            "cones=0",
            "colour=1",
            "voxels=32;voxels=64",
            "aperture=wide",
            "tiny|",
            "paper=2",
            "voxels=4,5,6,7,8,9,10,11,12,13;cones=1,2,3,4,5,6,7,8,9,10;step=1,2,3,4,0.5,0.25,0.3,0.4,0.6,0.7;bounces=1,2",
        ] {
            assert!(parse(bad).is_err(), "{bad:?} parsed");
        }
    }
}
