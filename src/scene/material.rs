//! Materials and their textures. Each glTF texture is decoded once per colour space it is
//! used in (sRGB for colours, linear for data), so the renderer can pick the right Vulkan
//! format without knowing how a texture is used.

use super::accessor::Buffers;
use super::load::{read_uri, UriError};
use super::{AlphaMode, Material, TexRef, Texture, Wrap};
use glam::{Vec3, Vec4};
use gltf::json;
use json::texture::{MagFilter, MinFilter, WrappingMode};
use json::validation::Checked;
use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

/// An image decoded to RGBA8.
struct Decoded {
    width: u32,
    height: u32,
    rgba8: Vec<u8>,
}

/// A texture slot of a material before textures exist: (index into `keys`, texcoord set).
type Slot = Option<(usize, u32)>;

struct Slots {
    base_color: Slot,
    metallic_roughness: Slot,
    normal: Slot,
    emissive: Slot,
    specular: Slot,
    specular_color: Slot,
}

/// Collects the distinct (glTF texture, colour space) pairs in order of first use.
struct TextureKeys<'a> {
    root: &'a json::Root,
    keys: Vec<(usize, bool)>,
    lookup: HashMap<(usize, bool), usize>,
}

impl TextureKeys<'_> {
    fn slot(
        &mut self,
        info: Option<(json::Index<json::Texture>, u32)>,
        srgb: bool,
        what: &str,
        material: &str,
        warnings: &mut Vec<String>,
    ) -> Slot {
        let (index, tex_coord) = info?;
        let t = index.value();
        let Some(texture) = self.root.textures.get(t) else {
            warnings.push(format!(
                "{material}: {what} texture {t} does not exist (the file has {} textures); ignored",
                self.root.textures.len()
            ));
            return None;
        };
        if texture.source.value() >= self.root.images.len() {
            // Already reported by `load_materials` for the texture itself.
            return None;
        }
        if tex_coord != 0 {
            warnings.push(format!(
                "{material}: {what} texture uses TEXCOORD_{tex_coord}; only TEXCOORD_0 is \
                 loaded, so it is used instead"
            ));
        }
        let next = self.keys.len();
        let k = *self.lookup.entry((t, srgb)).or_insert(next);
        if k == next {
            self.keys.push((t, srgb));
        }
        Some((k, tex_coord))
    }
}

fn info(i: &Option<json::texture::Info>) -> Option<(json::Index<json::Texture>, u32)> {
    i.as_ref().map(|i| (i.index, i.tex_coord))
}

/// Names a material in messages.
fn material_label(index: usize, m: &json::Material) -> String {
    match &m.name {
        Some(n) => format!("material {index} ('{n}')"),
        None => format!("material {index}"),
    }
}

/// Names an image (its file where it has one) in messages.
fn image_label(index: usize, image: &json::Image) -> String {
    match (&image.uri, &image.name) {
        (Some(uri), _) if !uri.starts_with("data:") => format!("image {index} '{uri}'"),
        (_, Some(name)) => format!("image {index} ('{name}')"),
        _ => format!("image {index}"),
    }
}

/// Reads and decodes one image; the error names the image and what went wrong.
fn decode_image(
    root: &json::Root,
    buffers: &Buffers,
    base: &Path,
    index: usize,
) -> Result<Decoded, String> {
    let image = &root.images[index];
    let label = image_label(index, image);
    let bytes: Vec<u8>;
    let data: &[u8] = match (&image.uri, image.buffer_view) {
        (Some(uri), _) => {
            bytes = read_uri(base, uri).map_err(|e| match e {
                UriError::Missing(p) => {
                    format!("{label}: the image file {} does not exist", p.display())
                }
                other => format!("{label}: {other}"),
            })?;
            &bytes
        }
        (None, Some(view)) => buffers
            .image_view(root, view.value(), &label)
            .map_err(|e| format!("{label}: {e}"))?,
        (None, None) => return Err(format!("{label} has neither a uri nor a bufferView")),
    };
    let format = image::guess_format(data).map_err(|_| {
        let mime = image.mime_type.as_ref().map(|m| m.0.as_str());
        format!(
            "{label} is not in a supported image format (PNG, JPEG or EXR){}",
            mime.map(|m| format!("; its mimeType is {m}"))
                .unwrap_or_default()
        )
    })?;
    // Decoders are third-party code fed with untrusted bytes: contain any panic to this image.
    let decoded = std::panic::catch_unwind(|| image::load_from_memory_with_format(data, format))
        .map_err(|_| format!("{label}: the {format:?} decoder failed"))?
        .map_err(|e| format!("{label} could not be decoded: {e}"))?;
    let rgba = decoded.to_rgba8();
    Ok(Decoded {
        width: rgba.width(),
        height: rgba.height(),
        rgba8: rgba.into_raw(),
    })
}

/// Decodes the listed images on all cores; failures become warnings and `None`.
fn decode_images(
    root: &json::Root,
    buffers: &Buffers,
    base: &Path,
    needed: &[usize],
    warnings: &mut Vec<String>,
) -> HashMap<usize, Decoded> {
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .clamp(1, 8)
        .min(needed.len().max(1));
    let next = AtomicUsize::new(0);
    let mut results: Vec<(usize, Result<Decoded, String>)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                s.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(&image) = needed.get(i) else { break };
                        done.push((i, decode_image(root, buffers, base, image)));
                    }
                    done
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_default())
            .collect()
    });
    // Keep warnings in file order whatever order the threads finished in.
    results.sort_by_key(|(i, _)| *i);
    let mut out = HashMap::new();
    for (i, r) in results {
        match r {
            Ok(d) => {
                out.insert(needed[i], d);
            }
            Err(e) => warnings.push(format!("{e}; textures using it are ignored")),
        }
    }
    out
}

fn wrap(w: Checked<WrappingMode>) -> Wrap {
    match w {
        Checked::Valid(WrappingMode::ClampToEdge) => Wrap::ClampToEdge,
        Checked::Valid(WrappingMode::MirroredRepeat) => Wrap::MirroredRepeat,
        _ => Wrap::Repeat,
    }
}

/// A finite value clamped to a range, or the default; `changed` records any fix.
fn fix(v: f32, default: f32, lo: f32, hi: f32, changed: &mut bool) -> f32 {
    if !v.is_finite() {
        *changed = true;
        return default;
    }
    let c = v.clamp(lo, hi);
    if c != v {
        *changed = true;
    }
    c
}

/// Converts all materials (same indices as in the file) and the textures they use.
pub fn load_materials(
    root: &json::Root,
    buffers: &Buffers,
    base: &Path,
    warnings: &mut Vec<String>,
) -> (Vec<Material>, Vec<Texture>) {
    warn_of_sourceless_textures(root, warnings);
    let mut keys = TextureKeys {
        root,
        keys: Vec::new(),
        lookup: HashMap::new(),
    };
    let all_slots: Vec<Slots> = root
        .materials
        .iter()
        .enumerate()
        .map(|(i, m)| material_slots(i, m, &mut keys, warnings))
        .collect();
    let (textures, key_texture) = make_textures(root, buffers, base, &keys.keys, warnings);
    let tex_ref = |slot: Slot| -> Option<TexRef> {
        let (k, tex_coord) = slot?;
        key_texture[k].map(|texture| TexRef { texture, tex_coord })
    };
    let materials = root
        .materials
        .iter()
        .zip(all_slots)
        .enumerate()
        .map(|(i, (m, slots))| material(i, m, &slots, &tex_ref, warnings))
        .collect();
    (materials, textures)
}

/// Warns of textures whose image is missing or given only by an unsupported extension.
fn warn_of_sourceless_textures(root: &json::Root, warnings: &mut Vec<String>) {
    for (t, tex) in root.textures.iter().enumerate() {
        let image = tex.source.value();
        // gltf-json marks a texture without `source` with u32::MAX.
        if image == u32::MAX as usize {
            warnings.push(format!(
                "texture {t} has no source image (only an extension source such as KTX2 or \
                 WebP, which is not supported); materials using it get no texture"
            ));
        } else if image >= root.images.len() {
            warnings.push(format!(
                "texture {t} uses image {image}, which does not exist (the file has {} images); \
                 materials using it get no texture",
                root.images.len()
            ));
        }
    }
}

/// Material `i`'s texture slots, each a key (texture, colour space) of `keys`.
fn material_slots(
    i: usize,
    m: &json::Material,
    keys: &mut TextureKeys<'_>,
    warnings: &mut Vec<String>,
) -> Slots {
    let label = material_label(i, m);
    let pbr = &m.pbr_metallic_roughness;
    let spec = m.extensions.as_ref().and_then(|e| e.specular.as_ref());
    let mut slot = |i: Option<(json::Index<json::Texture>, u32)>, srgb: bool, what: &str| {
        keys.slot(i, srgb, what, &label, warnings)
    };
    Slots {
        base_color: slot(info(&pbr.base_color_texture), true, "base colour"),
        metallic_roughness: slot(
            info(&pbr.metallic_roughness_texture),
            false,
            "metallic-roughness",
        ),
        normal: slot(
            m.normal_texture.as_ref().map(|n| (n.index, n.tex_coord)),
            false,
            "normal",
        ),
        emissive: slot(info(&m.emissive_texture), true, "emissive"),
        specular: slot(
            spec.and_then(|s| info(&s.specular_texture)),
            false,
            "specular",
        ),
        specular_color: slot(
            spec.and_then(|s| info(&s.specular_color_texture)),
            true,
            "specular colour",
        ),
    }
}

/// One texture per key (texture, colour space), each image decoded once whatever number of
/// colour spaces it is used in; and per key its index among them (None where the image did
/// not decode).
fn make_textures(
    root: &json::Root,
    buffers: &Buffers,
    base: &Path,
    keys: &[(usize, bool)],
    warnings: &mut Vec<String>,
) -> (Vec<Texture>, Vec<Option<u32>>) {
    let mut needed: Vec<usize> = keys
        .iter()
        .map(|&(t, _)| root.textures[t].source.value())
        .collect();
    needed.sort_unstable();
    needed.dedup();
    let mut decoded = decode_images(root, buffers, base, &needed, warnings);
    let mut uses: HashMap<usize, usize> = HashMap::new();
    for &(t, _) in keys {
        *uses.entry(root.textures[t].source.value()).or_default() += 1;
    }

    let mut textures = Vec::new();
    let mut key_texture: Vec<Option<u32>> = Vec::with_capacity(keys.len());
    for &(t, srgb) in keys {
        let image = root.textures[t].source.value();
        let left = uses.get_mut(&image).map(|u| {
            *u -= 1;
            *u
        });
        // The last user of a decoded image takes its pixels instead of copying them.
        let pixels = if left == Some(0) {
            decoded.remove(&image)
        } else {
            decoded.get(&image).map(|d| Decoded {
                width: d.width,
                height: d.height,
                rgba8: d.rgba8.clone(),
            })
        };
        let Some(pixels) = pixels else {
            key_texture.push(None);
            continue;
        };
        key_texture.push(Some(textures.len() as u32));
        textures.push(texture(root, t, srgb, pixels, warnings));
    }
    (textures, key_texture)
}

/// Texture `t` in one colour space, with its sampler's wrap and filters and a name.
fn texture(
    root: &json::Root,
    t: usize,
    srgb: bool,
    pixels: Decoded,
    warnings: &mut Vec<String>,
) -> Texture {
    let tex = &root.textures[t];
    let image = tex.source.value();
    let sampler = match tex.sampler {
        Some(s) => match root.samplers.get(s.value()) {
            Some(s) => Some(s),
            None => {
                warnings.push(format!(
                    "texture {t} uses sampler {}, which does not exist; default sampler used",
                    s.value()
                ));
                None
            }
        },
        None => None,
    };
    let default_sampler = json::texture::Sampler::default();
    let sampler = sampler.unwrap_or(&default_sampler);
    let name = tex
        .name
        .clone()
        .or_else(|| root.images[image].name.clone())
        .or_else(|| {
            root.images[image]
                .uri
                .clone()
                .filter(|u| !u.starts_with("data:"))
        })
        .unwrap_or_else(|| format!("texture {t}"));
    Texture {
        name,
        width: pixels.width,
        height: pixels.height,
        rgba8: pixels.rgba8,
        srgb,
        wrap_s: wrap(sampler.wrap_s),
        wrap_t: wrap(sampler.wrap_t),
        mag_nearest: matches!(sampler.mag_filter, Some(Checked::Valid(MagFilter::Nearest))),
        min_nearest: matches!(
            sampler.min_filter,
            Some(Checked::Valid(
                MinFilter::Nearest
                    | MinFilter::NearestMipmapNearest
                    | MinFilter::NearestMipmapLinear
            ))
        ),
    }
}

/// Material `i` from its JSON, its slots' textures through `tex_ref`; non-finite or
/// out-of-range factors are clamped with a warning.
fn material(
    i: usize,
    m: &json::Material,
    slots: &Slots,
    tex_ref: &dyn Fn(Slot) -> Option<TexRef>,
    warnings: &mut Vec<String>,
) -> Material {
    let mut changed = false;
    let pbr = &m.pbr_metallic_roughness;
    let bc = pbr.base_color_factor.0;
    let base_color = Vec4::new(
        fix(bc[0], 1.0, 0.0, 1.0, &mut changed),
        fix(bc[1], 1.0, 0.0, 1.0, &mut changed),
        fix(bc[2], 1.0, 0.0, 1.0, &mut changed),
        fix(bc[3], 1.0, 0.0, 1.0, &mut changed),
    );
    let strength = m
        .extensions
        .as_ref()
        .and_then(|e| e.emissive_strength.as_ref())
        .map_or(1.0, |s| s.emissive_strength.0);
    let strength = fix(strength, 1.0, 0.0, f32::MAX, &mut changed);
    let ef = m.emissive_factor.0;
    let emissive = Vec3::new(
        fix(ef[0], 0.0, 0.0, f32::MAX, &mut changed),
        fix(ef[1], 0.0, 0.0, f32::MAX, &mut changed),
        fix(ef[2], 0.0, 0.0, f32::MAX, &mut changed),
    ) * strength;
    let spec = m.extensions.as_ref().and_then(|e| e.specular.as_ref());
    let specular_factor = spec.map_or(1.0, |s| s.specular_factor.0);
    let sc = spec.map_or([1.0; 3], |s| s.specular_color_factor.0);
    let alpha_mode = match m.alpha_mode {
        Checked::Valid(json::material::AlphaMode::Opaque) => AlphaMode::Opaque,
        Checked::Valid(json::material::AlphaMode::Blend) => AlphaMode::Blend,
        Checked::Valid(json::material::AlphaMode::Mask) => AlphaMode::Mask(fix(
            m.alpha_cutoff.map_or(0.5, |c| c.0),
            0.5,
            0.0,
            f32::MAX,
            &mut changed,
        )),
        Checked::Invalid => {
            warnings.push(format!(
                "{} has an unknown alphaMode; treated as OPAQUE",
                material_label(i, m)
            ));
            AlphaMode::Opaque
        }
    };
    let material = Material {
        name: m.name.clone(),
        base_color,
        base_color_tex: tex_ref(slots.base_color),
        metallic: fix(pbr.metallic_factor.0, 1.0, 0.0, 1.0, &mut changed),
        roughness: fix(pbr.roughness_factor.0, 1.0, 0.0, 1.0, &mut changed),
        metallic_roughness_tex: tex_ref(slots.metallic_roughness),
        normal_tex: tex_ref(slots.normal),
        normal_scale: fix(
            m.normal_texture.as_ref().map_or(1.0, |n| n.scale),
            1.0,
            f32::MIN,
            f32::MAX,
            &mut changed,
        ),
        // Emission is radiance: infinite values would blow up every pixel they touch.
        emissive: if emissive.is_finite() {
            emissive
        } else {
            changed = true;
            Vec3::ZERO
        },
        emissive_tex: tex_ref(slots.emissive),
        specular_factor: fix(specular_factor, 1.0, 0.0, f32::MAX, &mut changed),
        specular_tex: tex_ref(slots.specular),
        specular_color: Vec3::new(
            fix(sc[0], 1.0, 0.0, f32::MAX, &mut changed),
            fix(sc[1], 1.0, 0.0, f32::MAX, &mut changed),
            fix(sc[2], 1.0, 0.0, f32::MAX, &mut changed),
        ),
        specular_color_tex: tex_ref(slots.specular_color),
        alpha_mode,
        double_sided: m.double_sided,
    };
    if changed {
        warnings.push(format!(
            "{} has non-finite or out-of-range factors; clamped to valid values",
            material_label(i, m)
        ));
    }
    material
}
