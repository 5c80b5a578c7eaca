//! Bounds-checked reading of glTF buffers, buffer views and accessors.
//!
//! The gltf crate's readers index slices directly and can panic (or silently truncate) on a
//! file whose accessors point outside their buffers, so every range is checked here and bad
//! data becomes an error message instead.

use gltf::json;
use json::accessor::{ComponentType, Type};
use json::validation::Checked;

/// Loaded buffer contents, each cut to its declared `byteLength`.
pub struct Buffers {
    pub data: Vec<Vec<u8>>,
}

/// Accessors with no buffer view are all zeros; this caps how many elements such an accessor
/// may claim, so a corrupt count cannot make us allocate gigabytes of zeros.
const MAX_VIEWLESS_ELEMENTS: u64 = 1 << 22;

pub fn component_size(c: ComponentType) -> usize {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

pub fn multiplicity(t: Type) -> usize {
    match t {
        Type::Scalar => 1,
        Type::Vec2 => 2,
        Type::Vec3 => 3,
        Type::Vec4 | Type::Mat2 => 4,
        Type::Mat3 => 9,
        Type::Mat4 => 16,
    }
}

pub fn type_name(t: Type) -> &'static str {
    match t {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

pub fn component_name(c: ComponentType) -> &'static str {
    match c {
        ComponentType::I8 => "BYTE",
        ComponentType::U8 => "UNSIGNED_BYTE",
        ComponentType::I16 => "SHORT",
        ComponentType::U16 => "UNSIGNED_SHORT",
        ComponentType::U32 => "UNSIGNED_INT",
        ComponentType::F32 => "FLOAT",
    }
}

/// The checked shape of an accessor.
#[derive(Clone, Copy, Debug)]
pub struct Shape {
    pub ty: Type,
    pub component: ComponentType,
    pub normalized: bool,
    pub count: usize,
}

impl Shape {
    pub fn describe(&self) -> String {
        format!(
            "{} {}{}",
            type_name(self.ty),
            component_name(self.component),
            if self.normalized { " (normalized)" } else { "" }
        )
    }
}

fn read_u32_le(b: &[u8]) -> u32 {
    u32::from_le_bytes([b[0], b[1], b[2], b[3]])
}

/// One component converted to f32, applying glTF's normalisation rules.
fn component_f32(b: &[u8], c: ComponentType, normalized: bool) -> f32 {
    match c {
        ComponentType::F32 => f32::from_bits(read_u32_le(b)),
        ComponentType::U8 if normalized => f32::from(b[0]) / 255.0,
        ComponentType::U16 if normalized => f32::from(u16::from_le_bytes([b[0], b[1]])) / 65535.0,
        ComponentType::I8 if normalized => (f32::from(b[0] as i8) / 127.0).max(-1.0),
        ComponentType::I16 if normalized => {
            (f32::from(i16::from_le_bytes([b[0], b[1]])) / 32767.0).max(-1.0)
        }
        ComponentType::U32 if normalized => (f64::from(read_u32_le(b)) / 4294967295.0) as f32,
        ComponentType::U8 => f32::from(b[0]),
        ComponentType::U16 => f32::from(u16::from_le_bytes([b[0], b[1]])),
        ComponentType::I8 => f32::from(b[0] as i8),
        ComponentType::I16 => f32::from(i16::from_le_bytes([b[0], b[1]])),
        ComponentType::U32 => read_u32_le(b) as f32,
    }
}

/// One unsigned integer component (index data).
fn component_u32(b: &[u8], c: ComponentType) -> u32 {
    match c {
        ComponentType::U8 | ComponentType::I8 => u32::from(b[0]),
        ComponentType::U16 | ComponentType::I16 => u32::from(u16::from_le_bytes([b[0], b[1]])),
        ComponentType::U32 | ComponentType::F32 => read_u32_le(b),
    }
}

impl Buffers {
    /// The bytes of a buffer view, checked against its buffer; also returns its byteStride.
    fn view<'a>(
        &'a self,
        root: &json::Root,
        view_index: usize,
        who: &str,
    ) -> Result<(&'a [u8], Option<usize>), String> {
        let view = root.buffer_views.get(view_index).ok_or_else(|| {
            format!(
                "{who} refers to bufferView {view_index}, but the file has only {} buffer views",
                root.buffer_views.len()
            )
        })?;
        let b = view.buffer.value();
        let data = self.data.get(b).ok_or_else(|| {
            format!(
                "bufferView {view_index} refers to buffer {b}, but the file has only {} buffers",
                self.data.len()
            )
        })?;
        let offset = view.byte_offset.map_or(0, |o| o.0);
        let length = view.byte_length.0;
        let end = offset.saturating_add(length);
        if end > data.len() as u64 {
            return Err(format!(
                "bufferView {view_index} (used by {who}) covers bytes {offset}..{end} of buffer {b}, \
                 which is only {} bytes long",
                data.len()
            ));
        }
        Ok((
            &data[offset as usize..end as usize],
            view.byte_stride.map(|s| s.0),
        ))
    }

    /// Bytes of a buffer view used for an image.
    pub fn image_view<'a>(
        &'a self,
        root: &json::Root,
        view_index: usize,
        who: &str,
    ) -> Result<&'a [u8], String> {
        self.view(root, view_index, who).map(|(bytes, _)| bytes)
    }

    /// Checks an accessor's index and declared type; `who` names its user for messages.
    pub fn shape(&self, root: &json::Root, index: usize, who: &str) -> Result<Shape, String> {
        let acc = root.accessors.get(index).ok_or_else(|| {
            format!(
                "{who} refers to accessor {index}, but the file has only {} accessors",
                root.accessors.len()
            )
        })?;
        let component = match acc.component_type {
            Checked::Valid(c) => c.0,
            Checked::Invalid => {
                return Err(format!(
                    "accessor {index} ({who}) has an invalid componentType"
                ))
            }
        };
        let ty = match acc.type_ {
            Checked::Valid(t) => t,
            Checked::Invalid => {
                return Err(format!("accessor {index} ({who}) has an invalid type"))
            }
        };
        let count = usize::try_from(acc.count.0)
            .map_err(|_| format!("accessor {index} ({who}) has an impossible count"))?;
        Ok(Shape {
            ty,
            component,
            normalized: acc.normalized,
            count,
        })
    }

    /// Reads every component of an accessor (count x multiplicity values), applying sparse
    /// substitution. `read` converts one component from its bytes.
    fn gather<T: Copy + Default>(
        &self,
        root: &json::Root,
        index: usize,
        who: &str,
        read: impl Fn(&[u8]) -> T,
    ) -> Result<Vec<T>, String> {
        let shape = self.shape(root, index, who)?;
        let acc = &root.accessors[index];
        if matches!(shape.ty, Type::Mat2 | Type::Mat3 | Type::Mat4) {
            // Matrix columns have alignment padding; no attribute we read uses them.
            return Err(format!(
                "accessor {index} ({who}) is a {} accessor, which is not usable here",
                type_name(shape.ty)
            ));
        }
        let csize = component_size(shape.component);
        let ncomp = multiplicity(shape.ty);
        let elem = csize * ncomp;
        let count = shape.count;
        let mut out: Vec<T>;
        match acc.buffer_view {
            Some(view_index) => {
                let who_acc = format!("accessor {index} ({who})");
                let (bytes, stride) = self.view(root, view_index.value(), &who_acc)?;
                let stride = stride.unwrap_or(elem);
                if stride < elem {
                    return Err(format!(
                        "accessor {index} ({who}): bufferView {} has byteStride {stride}, smaller \
                         than the {elem}-byte elements",
                        view_index.value()
                    ));
                }
                let offset = acc.byte_offset.map_or(0, |o| o.0);
                if count > 0 {
                    // Checked in u128 so no count or offset can overflow.
                    let end =
                        u128::from(offset) + (count as u128 - 1) * stride as u128 + elem as u128;
                    if end > bytes.len() as u128 {
                        return Err(format!(
                            "accessor {index} ({who}) is out of range: {count} elements of {elem} \
                             bytes (stride {stride}) from byte {offset} need {end} bytes, but \
                             bufferView {} has only {}",
                            view_index.value(),
                            bytes.len()
                        ));
                    }
                }
                let offset = offset as usize;
                out = Vec::with_capacity(count * ncomp);
                for i in 0..count {
                    let base = offset + i * stride;
                    for c in 0..ncomp {
                        let at = base + c * csize;
                        out.push(read(&bytes[at..at + csize]));
                    }
                }
            }
            None => {
                if acc.count.0 > MAX_VIEWLESS_ELEMENTS {
                    return Err(format!(
                        "accessor {index} ({who}) has no bufferView but claims {count} elements"
                    ));
                }
                out = vec![T::default(); count * ncomp];
            }
        }
        if let Some(sparse) = &acc.sparse {
            let scount = usize::try_from(sparse.count.0).unwrap_or(usize::MAX);
            if scount > count {
                return Err(format!(
                    "accessor {index} ({who}): sparse count {scount} exceeds the accessor count {count}"
                ));
            }
            let icomp = match sparse.indices.component_type {
                Checked::Valid(c) => c.0,
                Checked::Invalid => {
                    return Err(format!(
                        "accessor {index} ({who}): sparse indices have an invalid componentType"
                    ))
                }
            };
            let isize_ = component_size(icomp);
            let who_sparse = format!("sparse accessor {index} ({who})");
            let (ibytes, _) = self.view(root, sparse.indices.buffer_view.value(), &who_sparse)?;
            let (vbytes, _) = self.view(root, sparse.values.buffer_view.value(), &who_sparse)?;
            let ioff = sparse.indices.byte_offset.0;
            let voff = sparse.values.byte_offset.0;
            let iend = u128::from(ioff) + scount as u128 * isize_ as u128;
            let vend = u128::from(voff) + scount as u128 * elem as u128;
            if iend > ibytes.len() as u128 || vend > vbytes.len() as u128 {
                return Err(format!(
                    "sparse accessor {index} ({who}) is out of range of its buffer views"
                ));
            }
            for s in 0..scount {
                let at = ioff as usize + s * isize_;
                let target = component_u32(&ibytes[at..at + isize_], icomp) as usize;
                if target >= count {
                    return Err(format!(
                        "sparse accessor {index} ({who}) substitutes element {target}, beyond its \
                         {count} elements"
                    ));
                }
                for c in 0..ncomp {
                    let at = voff as usize + s * elem + c * csize;
                    out[target * ncomp + c] = read(&vbytes[at..at + csize]);
                }
            }
        }
        Ok(out)
    }

    /// Reads an accessor as f32 components (normalised integers converted).
    pub fn read_f32(&self, root: &json::Root, index: usize, who: &str) -> Result<Vec<f32>, String> {
        let shape = self.shape(root, index, who)?;
        self.gather(root, index, who, |b| {
            component_f32(b, shape.component, shape.normalized)
        })
    }

    /// Reads a SCALAR unsigned-integer accessor as indices.
    pub fn read_indices(
        &self,
        root: &json::Root,
        index: usize,
        who: &str,
    ) -> Result<Vec<u32>, String> {
        let shape = self.shape(root, index, who)?;
        let ok_component = matches!(
            shape.component,
            ComponentType::U8 | ComponentType::U16 | ComponentType::U32
        );
        if shape.ty != Type::Scalar || !ok_component {
            return Err(format!(
                "index accessor {index} ({who}) is {}; expected SCALAR UNSIGNED_BYTE, \
                 UNSIGNED_SHORT or UNSIGNED_INT",
                shape.describe()
            ));
        }
        self.gather(root, index, who, |b| component_u32(b, shape.component))
    }
}
