//! The scene corpus: generated scenes drawn from classes (interiors lit through openings,
//! emitters of every size, glossy materials, objects under near and far lights, scale), their
//! path-traced references, and the table of the renderer's error on them, per class.
//!
//! A corpus is a folder: each scene is `NAME.glb` (its camera and lights in the file) with
//! `NAME.json` beside it ([`SceneRecord`]: its class, seed, split, sky and drawn parameters).
//! Half of every class is held out ([`Split`]): defaults and fixes are chosen on the tune
//! half, and the held-out half is what the renderer is judged by. docs/corpus.md has the
//! commands and the tables.

mod classes;
pub mod compare;
mod draft;
mod draw;
pub mod reference;
pub mod run;
mod shapes;

pub use classes::Class;

use crate::output::write_bytes_atomic;
use crate::scene::{Environment, Scene};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Errors of the corpus commands, each naming the file or folder.
#[derive(Debug, thiserror::Error)]
pub enum CorpusError {
    #[error("{path}: {reason}")]
    Io { path: PathBuf, reason: String },
    #[error("{path}: not a scene record: {reason}")]
    Record { path: PathBuf, reason: String },
    #[error("{path}: not the results.json of a corpus run: {reason}")]
    Report { path: PathBuf, reason: String },
    #[error("{path}: no scenes (make them with `voxgi corpus generate --out {path}`)")]
    Empty { path: PathBuf },
    #[error("{path}: {reason}")]
    Scene { path: PathBuf, reason: String },
}

fn io_error(path: &Path, e: impl std::fmt::Display) -> CorpusError {
    CorpusError::Io {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
}

/// Which half of the corpus a scene belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Split {
    /// Defaults and fixes are chosen on these.
    Tune,
    /// Reported, never tuned on.
    HeldOut,
}

impl Split {
    /// The fixed rule: a class's even-numbered scenes tune, its odd-numbered ones are held
    /// out, whatever the corpus's seed, so that every class has as many of each.
    pub fn of(number: u32) -> Split {
        if number.is_multiple_of(2) {
            Split::Tune
        } else {
            Split::HeldOut
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Split::Tune => "tune",
            Split::HeldOut => "held-out",
        }
    }
}

/// What is written beside each scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneRecord {
    pub name: String,
    pub class: String,
    /// The scene's number within its class.
    pub number: u32,
    /// The seed its draws came from.
    pub seed: u64,
    pub split: Split,
    /// The glTF file, beside this record.
    pub file: String,
    /// A uniform sky's radiance (`--env R,G,B`), if any.
    pub sky: Option<[f32; 3]>,
    /// The drawn parameters, in words.
    pub description: String,
}

impl SceneRecord {
    /// The scene loaded as the corpus renders it: the file, with its sky.
    pub fn load(&self, dir: &Path) -> Result<Scene, CorpusError> {
        let path = dir.join(&self.file);
        let mut scene = crate::scene::load(&path).map_err(|e| CorpusError::Scene {
            path: path.clone(),
            reason: e.to_string(),
        })?;
        scene.environment = self.sky.map(|s| Environment::uniform(glam::Vec3::from(s)));
        Ok(scene)
    }

    /// The command-line options that render it as the corpus does (for a user's report).
    pub fn options(&self) -> String {
        match self.sky {
            Some([r, g, b]) => format!("--env {r},{g},{b}"),
            None => String::new(),
        }
    }
}

/// What `generate` makes: the class of scene `i` of `count` (the classes in turn).
pub fn plan(count: u32, classes: &[Class]) -> Vec<(Class, u32)> {
    (0..count)
        .map(|i| {
            let k = classes.len() as u32;
            (classes[(i % k) as usize], i / k)
        })
        .collect()
}

/// One scene: its glb bytes and record.
pub fn generate_one(corpus_seed: u64, class: Class, number: u32) -> (Vec<u8>, SceneRecord) {
    let seed = draw::scene_seed(corpus_seed, class.name(), number);
    let mut d = draw::Draw::new(seed);
    let (draft, scale, offset) = class.draw(&mut d);
    let name = format!("{}-{number:03}", class.name());
    let record = SceneRecord {
        file: format!("{name}.glb"),
        name,
        class: class.name().to_string(),
        number,
        seed,
        split: Split::of(number),
        sky: draft.sky,
        description: draft.notes.join("; "),
    };
    (draft.finish(scale, offset).to_glb(), record)
}

/// Writes `count` scenes (the classes in turn) drawn from `seed` into `dir`, each as
/// `NAME.glb` and `NAME.json`. The same seed writes the same bytes.
pub fn generate(
    dir: &Path,
    count: u32,
    seed: u64,
    classes: &[Class],
) -> Result<Vec<SceneRecord>, CorpusError> {
    std::fs::create_dir_all(dir).map_err(|e| io_error(dir, e))?;
    let mut records = Vec::new();
    for (class, number) in plan(count, classes) {
        let (glb, record) = generate_one(seed, class, number);
        let glb_path = dir.join(&record.file);
        write_bytes_atomic(&glb_path, &glb).map_err(|e| io_error(&glb_path, e))?;
        let json_path = dir.join(format!("{}.json", record.name));
        let json = serde_json::to_string_pretty(&record).expect("a record serializes") + "\n";
        write_bytes_atomic(&json_path, json.as_bytes()).map_err(|e| io_error(&json_path, e))?;
        records.push(record);
    }
    Ok(records)
}

/// The scene records of a corpus folder, by name.
pub fn records(dir: &Path) -> Result<Vec<SceneRecord>, CorpusError> {
    let entries = std::fs::read_dir(dir).map_err(|e| io_error(dir, e))?;
    let mut out = Vec::new();
    for entry in entries {
        let path = entry.map_err(|e| io_error(dir, e))?.path();
        if path.extension().and_then(|e| e.to_str()) != Some("json") {
            continue;
        }
        let text = std::fs::read_to_string(&path).map_err(|e| io_error(&path, e))?;
        let record: SceneRecord = serde_json::from_str(&text).map_err(|e| CorpusError::Record {
            path: path.clone(),
            reason: e.to_string(),
        })?;
        if Class::from_name(&record.class).is_none() {
            return Err(CorpusError::Record {
                path,
                reason: format!("no class {:?}", record.class),
            });
        }
        out.push(record);
    }
    if out.is_empty() {
        return Err(CorpusError::Empty {
            path: dir.to_path_buf(),
        });
    }
    out.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_split_halves_every_class() {
        let p = plan(40, &Class::ALL);
        for c in Class::ALL {
            let held = p
                .iter()
                .filter(|(k, n)| *k == c && Split::of(*n) == Split::HeldOut)
                .count();
            assert_eq!(held, 4, "{c:?}");
        }
    }

    #[test]
    fn the_same_seed_draws_the_same_bytes() {
        for c in Class::ALL {
            for n in 0..6 {
                let (a, ra) = generate_one(11, c, n);
                let (b, rb) = generate_one(11, c, n);
                assert_eq!(a, b, "{c:?} {n}");
                assert_eq!(ra, rb);
                let (other, _) = generate_one(12, c, n);
                assert_ne!(a, other, "{c:?} {n}: another seed drew the same scene");
            }
        }
    }
}
