//! A shader's interface as its SPIR-V states it: the descriptor bindings its entry point uses
//! (set, binding, name, type, whether it reads or writes each), the size of its push-constant
//! block and the member offsets of its blocks and structs. The GLSL is the one source of binding
//! numbers and layouts; the Rust side names bindings and is checked against this.

use ash::vk;

/// One descriptor binding a shader uses.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Binding {
    pub set: u32,
    pub binding: u32,
    /// The GLSL name: the variable's, or for a block declared without an instance name, the
    /// block's (`buffer Lights { .. };` is "Lights").
    pub name: String,
    pub ty: vk::DescriptorType,
    /// Descriptors in the binding (an array's length; 1 otherwise).
    pub count: u32,
    /// Whether the shader may read it (false only for `writeonly`).
    pub reads: bool,
    /// Whether the shader may write it (false for `readonly`, samplers and uniform blocks).
    pub writes: bool,
}

/// A struct's layout: each member's offset and size in bytes (as decorated for std140 or
/// std430), and the struct's size (its last member's end).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Struct {
    pub name: String,
    pub members: Vec<Member>,
    pub size: u32,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Member {
    pub name: String,
    pub offset: u32,
    pub size: u32,
}

/// What one shader module declares.
#[derive(Clone, Debug, Default)]
pub struct Interface {
    pub stage: vk::ShaderStageFlags,
    /// Sorted by set, then binding.
    pub bindings: Vec<Binding>,
    /// Bytes of the push-constant block (0 without one).
    pub push_constants: u32,
    /// Every struct with member offsets (blocks and the structs inside them).
    pub structs: Vec<Struct>,
}

impl Interface {
    pub fn binding(&self, set: u32, name: &str) -> Option<&Binding> {
        self.bindings
            .iter()
            .find(|b| b.set == set && b.name == name)
    }

    pub fn struct_named(&self, name: &str) -> Option<&Struct> {
        self.structs.iter().find(|s| s.name == name)
    }
}

// Opcodes, decorations and enumerants of the SPIR-V specification that this reads.
const OP_NAME: u32 = 5;
const OP_MEMBER_NAME: u32 = 6;
const OP_ENTRY_POINT: u32 = 15;
const OP_TYPE_BOOL: u32 = 20;
const OP_TYPE_INT: u32 = 21;
const OP_TYPE_FLOAT: u32 = 22;
const OP_TYPE_VECTOR: u32 = 23;
const OP_TYPE_MATRIX: u32 = 24;
const OP_TYPE_IMAGE: u32 = 25;
const OP_TYPE_SAMPLER: u32 = 26;
const OP_TYPE_SAMPLED_IMAGE: u32 = 27;
const OP_TYPE_ARRAY: u32 = 28;
const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_POINTER: u32 = 32;
const OP_CONSTANT: u32 = 43;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;

const DEC_BLOCK: u32 = 2;
const DEC_BUFFER_BLOCK: u32 = 3;
const DEC_ARRAY_STRIDE: u32 = 6;
const DEC_MATRIX_STRIDE: u32 = 7;
const DEC_NON_WRITABLE: u32 = 24;
const DEC_NON_READABLE: u32 = 25;
const DEC_BINDING: u32 = 33;
const DEC_DESCRIPTOR_SET: u32 = 34;
const DEC_OFFSET: u32 = 35;

const SC_UNIFORM_CONSTANT: u32 = 0;
const SC_UNIFORM: u32 = 2;
const SC_PUSH_CONSTANT: u32 = 9;
const SC_STORAGE_BUFFER: u32 = 12;

#[derive(Clone, Debug)]
enum Type {
    Scalar(u32),
    Vector(u32, u32),
    Matrix(u32, u32),
    Image {
        storage: bool,
    },
    Sampler,
    SampledImage,
    Array(u32, u32),
    RuntimeArray(u32),
    Struct(Vec<u32>),
    /// A pointer, to its pointee.
    Pointer(u32),
}

/// The decoded module: the facts the interface is built from.
#[derive(Default)]
struct Module {
    names: std::collections::HashMap<u32, String>,
    member_names: std::collections::HashMap<(u32, u32), String>,
    decorations: std::collections::HashMap<u32, Vec<(u32, u32)>>,
    member_decorations: std::collections::HashMap<(u32, u32), Vec<(u32, u32)>>,
    types: std::collections::HashMap<u32, Type>,
    constants: std::collections::HashMap<u32, u32>,
    /// (result id, pointer type, storage class), in order.
    variables: Vec<(u32, u32, u32)>,
    /// The execution model and the interface of the first entry point.
    entry: Option<(u32, Vec<u32>)>,
    version: u32,
}

impl Module {
    fn decoration(&self, id: u32, dec: u32) -> Option<u32> {
        self.decorations
            .get(&id)?
            .iter()
            .find(|(d, _)| *d == dec)
            .map(|(_, v)| *v)
    }
    fn member_decoration(&self, id: u32, member: u32, dec: u32) -> Option<u32> {
        self.member_decorations
            .get(&(id, member))?
            .iter()
            .find(|(d, _)| *d == dec)
            .map(|(_, v)| *v)
    }
    fn has(&self, id: u32, dec: u32) -> bool {
        self.decoration(id, dec).is_some()
    }
    /// Whether every member of struct `id` carries `dec` (glslang decorates a `readonly`
    /// block's members, not the block).
    fn all_members(&self, id: u32, dec: u32) -> bool {
        match self.types.get(&id) {
            Some(Type::Struct(m)) if !m.is_empty() => {
                (0..m.len() as u32).all(|i| self.member_decoration(id, i, dec).is_some())
            }
            _ => false,
        }
    }

    /// Bytes a value of type `id` takes; `matrix_stride` for a matrix member. Runtime arrays
    /// take none.
    fn size(&self, id: u32, matrix_stride: Option<u32>) -> u32 {
        match self.types.get(&id) {
            Some(Type::Scalar(bytes)) => *bytes,
            Some(Type::Vector(c, n)) => self.size(*c, None) * n,
            Some(Type::Matrix(col, n)) => match matrix_stride {
                Some(stride) => stride * n,
                None => self.size(*col, None) * n,
            },
            Some(Type::Array(e, len)) => {
                let stride = self
                    .decoration(id, DEC_ARRAY_STRIDE)
                    .unwrap_or_else(|| self.size(*e, matrix_stride));
                stride * self.constants.get(len).copied().unwrap_or(0)
            }
            Some(Type::Struct(_)) => self.layout(id).size,
            _ => 0,
        }
    }

    fn layout(&self, id: u32) -> Struct {
        let members = match self.types.get(&id) {
            Some(Type::Struct(m)) => m.clone(),
            _ => Vec::new(),
        };
        let members: Vec<Member> = members
            .iter()
            .enumerate()
            .map(|(i, &ty)| {
                let i = i as u32;
                let stride = self.member_decoration(id, i, DEC_MATRIX_STRIDE);
                Member {
                    name: self.member_names.get(&(id, i)).cloned().unwrap_or_default(),
                    offset: self.member_decoration(id, i, DEC_OFFSET).unwrap_or(0),
                    size: self.size(ty, stride),
                }
            })
            .collect();
        Struct {
            name: self.names.get(&id).cloned().unwrap_or_default(),
            size: members.iter().map(|m| m.offset + m.size).max().unwrap_or(0),
            members,
        }
    }
}

/// A literal string's text and the words it takes.
fn string(words: &[u32]) -> (String, usize) {
    let mut bytes = Vec::new();
    for (i, w) in words.iter().enumerate() {
        for b in w.to_le_bytes() {
            if b == 0 {
                return (String::from_utf8_lossy(&bytes).into_owned(), i + 1);
            }
            bytes.push(b);
        }
    }
    (String::from_utf8_lossy(&bytes).into_owned(), words.len())
}

fn decode(words: &[u32]) -> Result<Module, String> {
    if words.len() < 5 || words[0] != 0x0723_0203 {
        return Err("not SPIR-V (no magic number)".into());
    }
    let mut m = Module {
        version: words[1],
        ..Default::default()
    };
    let mut i = 5;
    while i < words.len() {
        let (op, len) = (words[i] & 0xffff, (words[i] >> 16) as usize);
        if len == 0 || i + len > words.len() {
            return Err(format!("a truncated instruction at word {i}"));
        }
        let a = &words[i + 1..i + len];
        let arg = |k: usize| a.get(k).copied().unwrap_or(0);
        match op {
            OP_NAME => {
                m.names.insert(arg(0), string(&a[1..]).0);
            }
            OP_MEMBER_NAME => {
                m.member_names.insert((arg(0), arg(1)), string(&a[2..]).0);
            }
            OP_ENTRY_POINT if m.entry.is_none() => {
                let (_, used) = string(&a[2..]);
                m.entry = Some((arg(0), a[2 + used..].to_vec()));
            }
            OP_DECORATE => m
                .decorations
                .entry(arg(0))
                .or_default()
                .push((arg(1), arg(2))),
            OP_MEMBER_DECORATE => m
                .member_decorations
                .entry((arg(0), arg(1)))
                .or_default()
                .push((arg(2), arg(3))),
            OP_TYPE_BOOL => {
                m.types.insert(arg(0), Type::Scalar(4));
            }
            OP_TYPE_INT | OP_TYPE_FLOAT => {
                m.types.insert(arg(0), Type::Scalar(arg(1) / 8));
            }
            OP_TYPE_VECTOR => {
                m.types.insert(arg(0), Type::Vector(arg(1), arg(2)));
            }
            OP_TYPE_MATRIX => {
                m.types.insert(arg(0), Type::Matrix(arg(1), arg(2)));
            }
            OP_TYPE_IMAGE => {
                m.types.insert(
                    arg(0),
                    Type::Image {
                        storage: arg(6) == 2,
                    },
                );
            }
            OP_TYPE_SAMPLER => {
                m.types.insert(arg(0), Type::Sampler);
            }
            OP_TYPE_SAMPLED_IMAGE => {
                m.types.insert(arg(0), Type::SampledImage);
            }
            OP_TYPE_ARRAY => {
                m.types.insert(arg(0), Type::Array(arg(1), arg(2)));
            }
            OP_TYPE_RUNTIME_ARRAY => {
                m.types.insert(arg(0), Type::RuntimeArray(arg(1)));
            }
            OP_TYPE_STRUCT => {
                m.types.insert(arg(0), Type::Struct(a[1..].to_vec()));
            }
            OP_TYPE_POINTER => {
                m.types.insert(arg(0), Type::Pointer(arg(2)));
            }
            OP_CONSTANT => {
                m.constants.insert(arg(1), arg(2));
            }
            OP_VARIABLE => m.variables.push((arg(1), arg(0), arg(2))),
            _ => {}
        }
        i += len;
    }
    Ok(m)
}

/// Reads a shader's interface from its SPIR-V words.
pub fn reflect(words: &[u32]) -> Result<Interface, String> {
    let m = decode(words)?;
    let (model, interface) = m.entry.clone().ok_or("no entry point")?;
    let stage = match model {
        0 => vk::ShaderStageFlags::VERTEX,
        3 => vk::ShaderStageFlags::GEOMETRY,
        4 => vk::ShaderStageFlags::FRAGMENT,
        5 => vk::ShaderStageFlags::COMPUTE,
        other => return Err(format!("execution model {other} is not one voxgi uses")),
    };
    // From SPIR-V 1.4 the entry point lists every global it uses; before, only its inputs and
    // outputs, so every declared variable counts.
    let lists_all = m.version >= 0x0001_0400;
    let used = |id: u32| !lists_all || interface.contains(&id);
    let mut out = Interface {
        stage,
        ..Default::default()
    };
    for &(id, pointer, class) in &m.variables {
        let Some(Type::Pointer(pointee)) = m.types.get(&pointer) else {
            continue;
        };
        let pointee = *pointee;
        if class == SC_PUSH_CONSTANT && used(id) {
            out.push_constants = out.push_constants.max(m.layout(pointee).size);
            continue;
        }
        let (Some(set), Some(binding)) = (
            m.decoration(id, DEC_DESCRIPTOR_SET),
            m.decoration(id, DEC_BINDING),
        ) else {
            continue;
        };
        if !used(id) {
            continue;
        }
        // An array of descriptors: its element and length.
        let (element, count) = match m.types.get(&pointee) {
            Some(Type::Array(e, len)) => (*e, m.constants.get(len).copied().unwrap_or(1)),
            Some(Type::RuntimeArray(e)) => (*e, 0),
            _ => (pointee, 1),
        };
        let var_name = m.names.get(&id).cloned().unwrap_or_default();
        let (ty, reads, writes, name) = match (m.types.get(&element), class) {
            (Some(Type::SampledImage), SC_UNIFORM_CONSTANT) => (
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                true,
                false,
                var_name,
            ),
            (Some(Type::Image { storage: true }), SC_UNIFORM_CONSTANT) => (
                vk::DescriptorType::STORAGE_IMAGE,
                !m.has(id, DEC_NON_READABLE),
                !m.has(id, DEC_NON_WRITABLE),
                var_name,
            ),
            (Some(Type::Image { storage: false }), SC_UNIFORM_CONSTANT) => {
                (vk::DescriptorType::SAMPLED_IMAGE, true, false, var_name)
            }
            (Some(Type::Sampler), SC_UNIFORM_CONSTANT) => {
                (vk::DescriptorType::SAMPLER, true, false, var_name)
            }
            (Some(Type::Struct(_)), SC_UNIFORM | SC_STORAGE_BUFFER) => {
                let storage = class == SC_STORAGE_BUFFER || m.has(element, DEC_BUFFER_BLOCK);
                let block = m.names.get(&element).cloned().unwrap_or_default();
                let name = if var_name.is_empty() { block } else { var_name };
                if storage {
                    let not = |dec: u32| m.has(id, dec) || m.all_members(element, dec);
                    (
                        vk::DescriptorType::STORAGE_BUFFER,
                        !not(DEC_NON_READABLE),
                        !not(DEC_NON_WRITABLE),
                        name,
                    )
                } else if m.has(element, DEC_BLOCK) {
                    (vk::DescriptorType::UNIFORM_BUFFER, true, false, name)
                } else {
                    continue;
                }
            }
            _ => continue,
        };
        out.bindings.push(Binding {
            set,
            binding,
            name,
            ty,
            count,
            reads,
            writes,
        });
    }
    out.bindings.sort_by_key(|b| (b.set, b.binding));
    let mut structs: Vec<u32> = m
        .types
        .iter()
        .filter(|(_, t)| matches!(t, Type::Struct(_)))
        .map(|(id, _)| *id)
        .filter(|id| m.member_decoration(*id, 0, DEC_OFFSET).is_some())
        .collect();
    structs.sort();
    out.structs = structs.into_iter().map(|id| m.layout(id)).collect();
    Ok(out)
}

/// Every compiled shader's interface, by name (reflected once).
pub fn all_interfaces() -> &'static [(String, Interface)] {
    static ALL: std::sync::OnceLock<Vec<(String, Interface)>> = std::sync::OnceLock::new();
    ALL.get_or_init(|| {
        crate::shaders::SPIRV
            .iter()
            .filter_map(|(name, _)| Some((name.to_string(), shader_interface(name).ok()?)))
            .collect()
    })
}

/// The reflected interface of a compiled shader ("file" or "file:VARIANT").
pub fn shader_interface(name: &str) -> Result<Interface, String> {
    let words = crate::shaders::words(name).ok_or_else(|| format!("no shader {name}"))?;
    reflect(&words).map_err(|e| format!("{name}: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use vk::DescriptorType as T;

    fn interface(name: &str) -> Interface {
        shader_interface(name).unwrap()
    }

    #[test]
    fn reads_bindings_names_types_and_access() {
        let i = interface("aniso_mip_base.comp");
        assert_eq!(i.stage, vk::ShaderStageFlags::COMPUTE);
        let radiance = i.binding(0, "radiance").expect("radiance");
        assert_eq!((radiance.binding, radiance.ty), (0, T::STORAGE_IMAGE));
        assert!(radiance.reads && !radiance.writes, "readonly");
        let face = i.binding(0, "face_pz").expect("face_pz");
        assert_eq!(face.binding, 6);
        assert!(!face.reads && face.writes, "writeonly");

        let i = interface("deferred_lighting.comp");
        let frame = i
            .binding(0, "frame")
            .expect("the frame block, by its instance name");
        assert_eq!((frame.binding, frame.ty), (0, T::UNIFORM_BUFFER));
        let lights = i
            .binding(0, "Lights")
            .expect("an anonymous block, by its block name");
        assert_eq!((lights.binding, lights.ty), (3, T::UNIFORM_BUFFER));
        let ltc = i.binding(0, "LtcTable").expect("a storage block");
        assert_eq!((ltc.binding, ltc.ty), (7, T::STORAGE_BUFFER));
        assert!(ltc.reads && !ltc.writes);
        let shadow = i.binding(1, "shadow_map").unwrap();
        assert_eq!((shadow.binding, shadow.ty), (5, T::COMBINED_IMAGE_SAMPLER));

        let i = interface("voxel_list.comp");
        let list = i.binding(1, "VoxelList").unwrap();
        assert!(list.reads && list.writes, "a buffer without qualifiers");
    }

    #[test]
    fn reads_push_constants_and_leaves_out_what_a_variant_does_not_use() {
        assert_eq!(interface("gbuffer.vert").push_constants, 72);
        assert_eq!(interface("bounce_tail.comp").push_constants, 8);
        assert_eq!(interface("inject_radiance.comp").push_constants, 0);
        // The paper's light injection has no light-direction volume.
        assert!(interface("inject_radiance.comp")
            .binding(1, "emit_dir")
            .is_some());
        assert!(interface("inject_radiance.comp:PAPER")
            .binding(1, "emit_dir")
            .is_none());
    }

    #[test]
    fn reads_block_layouts() {
        let i = interface("deferred_lighting.comp");
        let frame = i.struct_named("Frame").expect("the Frame block");
        let view = frame.members.iter().find(|m| m.name == "view").unwrap();
        assert_eq!((view.offset, view.size), (64, 64));
        let cones = frame.members.iter().find(|m| m.name == "cones").unwrap();
        assert_eq!(cones.size, 16 * 16);
    }

    #[test]
    fn every_compiled_shader_reflects() {
        for (name, _) in crate::shaders::SPIRV {
            let i = shader_interface(name).unwrap();
            assert!(!i.stage.is_empty(), "{name}");
        }
        assert_eq!(all_interfaces().len(), crate::shaders::SPIRV.len());
    }

    #[test]
    fn rejects_what_is_not_spirv() {
        assert!(reflect(&[1, 2, 3, 4, 5]).is_err());
        assert!(reflect(&[0x0723_0203, 0x10500, 0, 10, 0, 0xffff_0001]).is_err());
    }
}
