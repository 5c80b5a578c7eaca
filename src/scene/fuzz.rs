//! A mutation fuzzer for the glTF and GLB loader, on stable Rust: seeds (the bundled Cornell
//! box, scenes made with the builder, glTF models given by path) damaged in the ways that reach
//! the loader's checks: bytes flipped, inserted or cut, JSON numbers set to awkward values
//! (counts, offsets, indices, enums), and whole structures broken (node cycles, hierarchies
//! ten thousand deep, accessors beyond their buffers, keys removed or of another type). Every
//! case must either load into a scene that passes [`Scene::check`] or fail with a one-line
//! error that names the file; a panic, a case slower than the time limit, or any other outcome
//! is a finding.

use super::builder::{self, LightDesc, LightType, NodeDesc};
use super::{load, Scene};
use gltf::json::Value;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

/// A file to damage: its bytes, and the directory of the files it refers to (buffers, images).
#[derive(Clone)]
pub struct Seed {
    pub name: String,
    pub bytes: Vec<u8>,
    pub glb: bool,
    /// Copied beside every damaged copy (None: the seed refers to no other file).
    pub dir: Option<PathBuf>,
}

impl Seed {
    /// A glTF or GLB file; the files beside it are copied along (a few MiB at most).
    pub fn from_file(path: &Path) -> Result<Seed, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let glb = bytes.starts_with(b"glTF");
        Ok(Seed {
            name: path
                .file_stem()
                .map_or("seed".into(), |s| s.to_string_lossy().into_owned()),
            bytes,
            glb,
            dir: path.parent().map(Path::to_path_buf),
        })
    }

    /// The bundled Cornell box with what it lacks (a spot light, a camera, a child node,
    /// unindexed triangles), as .gltf with an embedded buffer and as .glb.
    pub fn builtin() -> Vec<Seed> {
        let mut b = builder::default_cornell_box();
        let spot = b.add_light(LightDesc::new(
            "spot",
            LightType::Spot {
                inner_cone_angle: 0.2,
                outer_cone_angle: 0.5,
            },
            [1.0; 3],
            3.0,
        ));
        let tri = b.add_triangles(
            "tri",
            &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            None,
            None,
        );
        let cam = b.add_camera(builder::CameraDesc {
            name: None,
            yfov: 0.8,
            znear: 0.1,
            zfar: None,
            aspect_ratio: None,
        });
        let child = b.add_node(NodeDesc::new("tri").mesh(tri).light(spot));
        b.add_node(NodeDesc::new("cam").camera(cam).child(child));
        vec![
            Seed {
                name: "cornell-box".into(),
                bytes: b.to_gltf().into_bytes(),
                glb: false,
                dir: None,
            },
            Seed {
                name: "cornell-box".into(),
                bytes: b.to_glb(),
                glb: true,
                dir: None,
            },
        ]
    }
}

/// What a run does.
#[derive(Clone)]
pub struct FuzzSettings {
    pub cases: u64,
    /// Of the random sequence: the same seed gives the same cases.
    pub seed: u64,
    /// A case that takes longer is a finding (a hang).
    pub time_limit: Duration,
    /// Where the damaged files are written (one directory per worker).
    pub scratch: PathBuf,
    pub threads: usize,
}

/// How a case went wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FindingKind {
    Panic,
    Hang,
    /// The error spans lines, or does not name the file.
    UnclearError,
    /// It loaded into a scene the renderer cannot use.
    IllFormed,
}

#[derive(Clone, Debug)]
pub struct Finding {
    pub kind: FindingKind,
    pub case: u64,
    pub seed: String,
    pub mutation: String,
    pub message: String,
    /// The damaged file, kept.
    pub file: PathBuf,
}

#[derive(Clone, Debug, Default)]
pub struct FuzzReport {
    pub cases: u64,
    pub loaded: u64,
    pub rejected: u64,
    pub findings: Vec<Finding>,
    /// The slowest case that finished.
    pub slowest: Duration,
}

/// A small, fast random sequence (xorshift64*).
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Rng {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// JSON numbers that reach the loader's checks: indices just past the end, counts and
/// offsets that overflow 32 bits, enums of other kinds, negative and fractional values.
const AWKWARD: [f64; 18] = [
    0.0,
    1.0,
    2.0,
    3.0,
    4.0,
    5.0,
    7.0,
    255.0,
    65535.0,
    4294967295.0,
    4294967296.0,
    1e12,
    -1.0,
    0.5,
    1e30,
    -1e308,
    5126.0,
    34963.0,
];

/// The GLB container's JSON and BIN chunks (None: not a container this can split).
fn split_glb(bytes: &[u8]) -> Option<(Vec<u8>, Option<Vec<u8>>)> {
    let u32_at = |at: usize| -> Option<usize> {
        Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?) as usize)
    };
    let json_len = u32_at(12)?;
    let json = bytes.get(20..20 + json_len)?.to_vec();
    let bin = u32_at(20 + json_len)
        .and_then(|len| bytes.get(28 + json_len..28 + json_len + len))
        .map(<[u8]>::to_vec);
    Some((json, bin))
}

/// A GLB container around the chunks (each padded to 4 bytes).
fn join_glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let mut json = json.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend(0u32.to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    if let Some(bin) = bin {
        let mut bin = bin.to_vec();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(&bin);
    }
    let total = out.len() as u32;
    out[8..12].copy_from_slice(&total.to_le_bytes());
    out
}

/// JSON pointers to every value in `v` below the root that `keep` accepts.
fn pointers(v: &Value, at: String, keep: fn(&Value) -> bool, out: &mut Vec<String>) {
    if !at.is_empty() && keep(v) {
        out.push(at.clone());
    }
    match v {
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                pointers(x, format!("{at}/{i}"), keep, out);
            }
        }
        Value::Object(o) => {
            for (k, x) in o {
                let k = k.replace('~', "~0").replace('/', "~1");
                pointers(x, format!("{at}/{k}"), keep, out);
            }
        }
        _ => {}
    }
}

fn number(x: f64) -> Value {
    if x.fract() == 0.0 && (0.0..1e19).contains(&x) {
        Value::from(x as u64)
    } else {
        Value::from(x)
    }
}

/// Breaks one structure of the document; returns what it did.
fn break_structure(v: &mut Value, rng: &mut Rng) -> String {
    let count = |v: &Value, key: &str| v.get(key).and_then(Value::as_array).map_or(0, Vec::len);
    let nodes = count(v, "nodes");
    match rng.below(7) {
        0 if nodes > 0 => {
            // A cycle: a node's child is itself or its parent's parent.
            let (a, b) = (rng.below(nodes), rng.below(nodes));
            let node = &mut v["nodes"][a];
            let children = node
                .as_object_mut()
                .map(|o| o.entry("children").or_insert(Value::Array(Vec::new())));
            if let Some(Value::Array(c)) = children {
                c.push(Value::from(b as u64));
            }
            format!("node {a} gets child {b}")
        }
        1 => {
            // A chain of 10,000 nodes under the first scene's first root.
            let first = nodes;
            let depth = 10_000;
            let list = v
                .as_object_mut()
                .map(|o| o.entry("nodes").or_insert(Value::Array(Vec::new())));
            if let Some(Value::Array(list)) = list {
                for k in 0..depth {
                    let mut n = Value::Object(Default::default());
                    if k + 1 < depth {
                        n["children"] = Value::from(vec![first + k + 1]);
                    }
                    n["mesh"] = Value::from(0u64);
                    n["translation"] = Value::from(vec![0.001, 0.0, 0.0]);
                    list.push(n);
                }
            }
            if let Some(Value::Array(roots)) = v.pointer_mut("/scenes/0/nodes") {
                roots.push(Value::from(first as u64));
            }
            format!("a chain of {depth} nodes")
        }
        2 if count(v, "accessors") > 0 => {
            let a = rng.below(count(v, "accessors"));
            let (key, x) = match rng.below(3) {
                0 => ("count", 4294967295.0),
                1 => ("byteOffset", 4294967292.0),
                _ => ("count", 1e9),
            };
            v["accessors"][a][key] = number(x);
            format!("accessor {a} {key} {x}")
        }
        3 if count(v, "bufferViews") > 0 => {
            let b = rng.below(count(v, "bufferViews"));
            let key = ["byteLength", "byteOffset", "byteStride"][rng.below(3)];
            let x = AWKWARD[rng.below(AWKWARD.len())];
            v["bufferViews"][b][key] = number(x);
            format!("bufferView {b} {key} {x}")
        }
        4 => {
            let mut all = Vec::new();
            pointers(v, String::new(), |_| true, &mut all);
            let Some(target) = all.get(rng.below(all.len())).cloned() else {
                return "nothing".into();
            };
            let (parent, key) = target.rsplit_once('/').unwrap_or(("", &target));
            match v.pointer_mut(parent) {
                Some(Value::Object(o)) => {
                    o.remove(&key.replace("~1", "/").replace("~0", "~"));
                }
                Some(Value::Array(a)) => {
                    if let Ok(i) = key.parse::<usize>() {
                        if i < a.len() {
                            a.remove(i);
                        }
                    }
                }
                _ => {}
            }
            format!("{target} removed")
        }
        5 => {
            let mut all = Vec::new();
            pointers(v, String::new(), |_| true, &mut all);
            let Some(target) = all.get(rng.below(all.len())).cloned() else {
                return "nothing".into();
            };
            let other = match rng.below(4) {
                0 => Value::from("text"),
                1 => Value::Array(Vec::new()),
                2 => Value::Object(Default::default()),
                _ => Value::Null,
            };
            if let Some(x) = v.pointer_mut(&target) {
                *x = other;
            }
            format!("{target} of another type")
        }
        _ => {
            // Many copies of an entry: materials, meshes or nodes by the thousand.
            let key = ["materials", "meshes", "nodes", "textures"][rng.below(4)];
            if let Some(Value::Array(a)) = v.get_mut(key) {
                if let Some(first) = a.first().cloned() {
                    a.extend(std::iter::repeat_n(first, 5000));
                }
            }
            format!("5000 more {key}")
        }
    }
}

/// The JSON of a seed damaged: numbers set to awkward values, or a structure broken.
fn damage_json(json: &[u8], rng: &mut Rng) -> Option<(Vec<u8>, String)> {
    let mut v: Value = gltf::json::deserialize::from_slice(json).ok()?;
    let what = if rng.below(2) == 0 {
        let mut paths = Vec::new();
        pointers(&v, String::new(), Value::is_number, &mut paths);
        let mut done = Vec::new();
        for _ in 0..1 + rng.below(3) {
            let Some(target) = paths.get(rng.below(paths.len())) else {
                break;
            };
            let x = AWKWARD[rng.below(AWKWARD.len())];
            if let Some(slot) = v.pointer_mut(target) {
                *slot = number(x);
            }
            done.push(format!("{target} = {x}"));
        }
        done.join(", ")
    } else {
        break_structure(&mut v, rng)
    };
    Some((gltf::json::serialize::to_vec(&v).ok()?, what))
}

/// Case `case` of a run: a seed and its damage, as bytes and a description.
pub fn mutate(seeds: &[Seed], run_seed: u64, case: u64) -> (usize, Vec<u8>, String) {
    let mut rng = Rng::new(run_seed ^ case.wrapping_mul(0xD1B5_4A32_D192_ED03));
    let s = rng.below(seeds.len());
    let seed = &seeds[s];
    let mut bytes = seed.bytes.clone();
    let what = match rng.below(5) {
        0 => {
            let n = 1 + rng.below(8);
            for _ in 0..n {
                // The GLB header and chunk headers get their share.
                let at = if seed.glb && rng.below(2) == 0 {
                    rng.below(28.min(bytes.len()))
                } else {
                    rng.below(bytes.len())
                };
                if let Some(b) = bytes.get_mut(at) {
                    *b = rng.next() as u8;
                }
            }
            format!("{n} bytes set")
        }
        1 => {
            let cut = rng.below(bytes.len());
            bytes.truncate(cut);
            format!("cut at {cut}")
        }
        2 => {
            let at = rng.below(bytes.len() + 1);
            let n = 1 + rng.below(16);
            let junk: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
            bytes.splice(at..at, junk);
            format!("{n} bytes inserted at {at}")
        }
        _ => {
            let damaged = if seed.glb {
                split_glb(&bytes).and_then(|(json, bin)| {
                    let (json, what) = damage_json(&json, &mut rng)?;
                    Some((join_glb(&json, bin.as_deref()), what))
                })
            } else {
                damage_json(&bytes, &mut rng)
            };
            match damaged {
                Some((b, what)) => {
                    bytes = b;
                    what
                }
                None => "unchanged".into(),
            }
        }
    };
    (s, bytes, what)
}

/// A worker's case and since when (None between cases).
type Busy = Mutex<Option<(u64, Instant)>>;

/// One case's outcome.
enum Outcome {
    Loaded(Result<(), String>),
    Rejected(String),
    Panicked(String),
}

/// Loads `path`, catching a panic; a scene that loads is checked.
fn try_load(path: &Path) -> Outcome {
    match std::panic::catch_unwind(|| load(path).map(|s: Scene| s.check())) {
        Ok(Ok(checked)) => Outcome::Loaded(checked),
        Ok(Err(e)) => Outcome::Rejected(e.to_string()),
        Err(p) => Outcome::Panicked(
            p.downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "a panic".into()),
        ),
    }
}

/// Copies the files a seed refers to into `dir` (the seed's own file excluded).
fn copy_beside(seed: &Seed, dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let Some(from) = &seed.dir else {
        return Ok(());
    };
    for e in std::fs::read_dir(from)? {
        let e = e?;
        if e.file_type()?.is_file() {
            std::fs::copy(e.path(), dir.join(e.file_name()))?;
        }
    }
    Ok(())
}

/// Runs the cases on `settings.threads` workers. Stops early at a hang (its worker cannot be
/// stopped); everything else is counted and the run goes on.
pub fn run(seeds: &[Seed], settings: &FuzzSettings) -> std::io::Result<FuzzReport> {
    let threads = settings.threads.max(1);
    // Each worker's copy of each seed's directory.
    for w in 0..threads {
        for (k, seed) in seeds.iter().enumerate() {
            copy_beside(seed, &settings.scratch.join(format!("w{w}/s{k}")))?;
        }
    }
    let next = Arc::new(AtomicU64::new(0));
    let stop = Arc::new(AtomicBool::new(false));
    // Per worker: the case it is on and since when.
    let started: Arc<Vec<Busy>> = Arc::new((0..threads).map(|_| Mutex::new(None)).collect());
    let (tx, rx) = mpsc::channel::<(u64, usize, String, PathBuf, Outcome, Duration)>();
    let seeds = Arc::new(seeds.to_vec());
    for w in 0..threads {
        let (next, stop, started, tx, seeds) = (
            next.clone(),
            stop.clone(),
            started.clone(),
            tx.clone(),
            seeds.clone(),
        );
        let (cases, run_seed, scratch) = (settings.cases, settings.seed, settings.scratch.clone());
        std::thread::spawn(move || loop {
            let case = next.fetch_add(1, Ordering::Relaxed);
            if case >= cases || stop.load(Ordering::Relaxed) {
                break;
            }
            let (s, bytes, what) = mutate(&seeds, run_seed, case);
            let ext = if seeds[s].glb { "glb" } else { "gltf" };
            let path = scratch.join(format!("w{w}/s{s}/case.{ext}"));
            if std::fs::write(&path, &bytes).is_err() {
                break;
            }
            *started[w].lock().unwrap_or_else(|e| e.into_inner()) = Some((case, Instant::now()));
            let t = Instant::now();
            let outcome = try_load(&path);
            let took = t.elapsed();
            *started[w].lock().unwrap_or_else(|e| e.into_inner()) = None;
            if tx.send((case, s, what, path, outcome, took)).is_err() {
                break;
            }
        });
    }
    drop(tx);
    let mut report = FuzzReport::default();
    let bar = crate::console::bar(settings.cases, "fuzzing the loader, cases");
    let keep = |path: &Path, case: u64| -> PathBuf {
        let kept = settings.scratch.join(format!(
            "finding-{case}.{}",
            path.extension().and_then(|e| e.to_str()).unwrap_or("gltf")
        ));
        let _ = std::fs::copy(path, &kept);
        kept
    };
    loop {
        match rx.recv_timeout(Duration::from_millis(100)) {
            Ok((case, s, mutation, path, outcome, took)) => {
                report.cases += 1;
                bar.inc(1);
                report.slowest = report.slowest.max(took);
                let seed = seeds[s].name.clone();
                let mut finding = |kind, message: String| {
                    report.findings.push(Finding {
                        kind,
                        case,
                        seed: seed.clone(),
                        mutation: mutation.clone(),
                        message,
                        file: keep(&path, case),
                    })
                };
                match outcome {
                    Outcome::Loaded(Ok(())) => report.loaded += 1,
                    Outcome::Loaded(Err(e)) => finding(FindingKind::IllFormed, e),
                    Outcome::Rejected(e) => {
                        report.rejected += 1;
                        let named = e.contains(&path.display().to_string());
                        if e.contains('\n') || !named {
                            finding(FindingKind::UnclearError, e);
                        }
                    }
                    Outcome::Panicked(m) => finding(FindingKind::Panic, m),
                }
                if took > settings.time_limit {
                    finding(
                        FindingKind::Hang,
                        format!("took {:.1} s", took.as_secs_f64()),
                    );
                }
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {
                for slot in started.iter() {
                    let slot = *slot.lock().unwrap_or_else(|e| e.into_inner());
                    if let Some((case, since)) = slot {
                        if since.elapsed() > settings.time_limit {
                            stop.store(true, Ordering::Relaxed);
                            let (s, _, mutation) = mutate(&seeds, settings.seed, case);
                            report.findings.push(Finding {
                                kind: FindingKind::Hang,
                                case,
                                seed: seeds[s].name.clone(),
                                mutation,
                                message: format!(
                                    "still loading after {:.0} s",
                                    since.elapsed().as_secs_f64()
                                ),
                                file: PathBuf::new(),
                            });
                            return Ok(report);
                        }
                    }
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => return Ok(report),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_glb_splits_and_joins_back() {
        let seeds = Seed::builtin();
        let glb = &seeds[1].bytes;
        let (json, bin) = split_glb(glb).expect("chunks");
        assert_eq!(&join_glb(&json, bin.as_deref()), glb);
    }

    #[test]
    fn cases_are_reproducible_and_varied() {
        let seeds = Seed::builtin();
        let a: Vec<_> = (0..50).map(|c| mutate(&seeds, 7, c).1).collect();
        let b: Vec<_> = (0..50).map(|c| mutate(&seeds, 7, c).1).collect();
        assert_eq!(a, b);
        let distinct: std::collections::HashSet<_> = a.iter().collect();
        assert!(distinct.len() > 45, "{} distinct of 50", distinct.len());
        let changed = a
            .iter()
            .filter(|x| *x != &seeds[0].bytes && *x != &seeds[1].bytes)
            .count();
        assert!(changed > 45, "{changed} of 50 changed");
    }
}
