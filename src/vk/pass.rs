//! A pass's binding table and the pipeline made from it. Each entry of a [`Bindings`] table
//! names a binding of the pass's shaders by its GLSL name, the resource bound there and how the
//! pass uses it; the one table both writes the pass's descriptor sets and declares its accesses
//! to the graph, so the two cannot drift. The binding numbers, the set each binding lives in
//! and its type come from the shaders' SPIR-V ([`super::reflect`]); a table that disagrees with
//! its shaders (a binding they use that it lacks, another type, a read declared where the
//! shader writes) fails when the pass is made, naming the pass and the binding.
//!
//! Buffers the shaders reach through device addresses (GL_EXT_buffer_reference) have no
//! descriptor, and synchronization validation cannot see their accesses. A table binds the
//! buffer of addresses ([`AddressTable`]) and declares an access of each buffer it points to
//! with [`Bindings::reaches`]; a pass whose shaders use the table without declaring each of
//! them fails when it is made.

use super::graph::{Access, Graph, PassBuilder, Tracked};
use super::pipeline::{
    self, DescriptorPool, GraphicsDesc, LayoutBinding, Pipeline, SetLayout, Shader,
};
use super::{Buffer, Context, Image, Sampler, VkError, VkResult};
use ash::vk;
use std::sync::Arc;

/// How a pass uses a binding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Usage {
    Read,
    Write,
    ReadWrite,
    /// Read by the shader and as the arguments of an indirect dispatch.
    Indirect,
}

impl Usage {
    /// Both uses in one pass.
    fn and(self, other: Usage) -> Usage {
        use Usage::*;
        match (self, other) {
            (a, b) if a == b => a,
            (Indirect, Read) | (Read, Indirect) => Indirect,
            _ => ReadWrite,
        }
    }
    fn reads(self) -> bool {
        self != Usage::Write
    }
    fn writes(self) -> bool {
        matches!(self, Usage::Write | Usage::ReadWrite)
    }
}

/// What a binding holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum What {
    StorageImage(vk::ImageView),
    Sampled(vk::ImageView, vk::Sampler),
    StorageBuffer(vk::Buffer),
    /// A buffer and the bytes of it bound (offset, range).
    Uniform(vk::Buffer, u64, u64),
}

impl What {
    fn ty(self) -> vk::DescriptorType {
        match self {
            What::StorageImage(_) => vk::DescriptorType::STORAGE_IMAGE,
            What::Sampled(..) => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            What::StorageBuffer(_) => vk::DescriptorType::STORAGE_BUFFER,
            What::Uniform(..) => vk::DescriptorType::UNIFORM_BUFFER,
        }
    }
}

#[derive(Clone, Debug)]
struct Entry {
    name: String,
    what: What,
    tracked: Tracked,
    usage: Usage,
    /// The bound resource's name, for messages.
    resource: String,
    /// For a buffer of device addresses: the buffers it points to.
    addresses: Vec<(vk::Buffer, String)>,
}

/// A small buffer of device addresses that shaders read to reach larger buffers (the voxel
/// words: a 512^3 grid's are larger than a storage descriptor may span).
pub struct AddressTable {
    pub buffer: Buffer,
    /// The buffers it points to (absent ones are address 0 and not listed).
    pub targets: Vec<(vk::Buffer, String)>,
}

impl AddressTable {
    /// A host-visible table of the buffers' addresses, in order (0 for None).
    pub fn new(ctx: &Arc<Context>, name: &str, buffers: &[Option<&Buffer>]) -> VkResult<Self> {
        let bytes: Vec<u8> = buffers
            .iter()
            .flat_map(|b| b.map_or(0, |b| b.address()).to_le_bytes())
            .collect();
        let buffer = Buffer::with_data(ctx, name, &bytes, vk::BufferUsageFlags::STORAGE_BUFFER)?;
        Ok(AddressTable {
            buffer,
            targets: buffers
                .iter()
                .flatten()
                .map(|b| (b.raw, b.name.clone()))
                .collect(),
        })
    }
}

/// A pass's binding table: what is bound to each binding its shaders name, and how the pass
/// uses it.
#[derive(Clone, Debug, Default)]
pub struct Bindings {
    entries: Vec<Entry>,
    /// Declared accesses of buffers reached through addresses.
    reached: Vec<(vk::Buffer, String, Usage)>,
}

impl Bindings {
    pub fn new() -> Self {
        Self::default()
    }

    fn push(mut self, name: &str, what: What, tracked: Tracked, usage: Usage, res: &str) -> Self {
        self.entries.push(Entry {
            name: name.into(),
            what,
            tracked,
            usage,
            resource: res.into(),
            addresses: Vec::new(),
        });
        self
    }

    /// A storage image (all of it).
    pub fn image(self, name: &str, image: &Image, usage: Usage) -> Self {
        self.image_view(name, image, image.view, usage)
    }

    /// A storage image through one of its views (a mip level); the graph tracks the image.
    pub fn image_view(self, name: &str, image: &Image, view: vk::ImageView, usage: Usage) -> Self {
        let tracked = Tracked::image(image);
        self.push(name, What::StorageImage(view), tracked, usage, &image.name)
    }

    /// A combined image sampler (read in SHADER_READ_ONLY_OPTIMAL).
    pub fn sampled(self, name: &str, image: &Image, sampler: &Sampler) -> Self {
        self.sampled_with(name, image, sampler.raw)
    }

    pub fn sampled_with(self, name: &str, image: &Image, sampler: vk::Sampler) -> Self {
        let what = What::Sampled(image.view, sampler);
        self.push(name, what, Tracked::image(image), Usage::Read, &image.name)
    }

    /// A storage buffer.
    pub fn buffer(self, name: &str, buffer: &Buffer, usage: Usage) -> Self {
        let what = What::StorageBuffer(buffer.raw);
        self.push(name, what, Tracked::Buffer(buffer.raw), usage, &buffer.name)
    }

    /// A uniform buffer.
    pub fn uniform(self, name: &str, buffer: &Buffer) -> Self {
        self.uniform_range(name, buffer, 0, vk::WHOLE_SIZE)
    }

    /// Part of a uniform buffer: `range` bytes from `offset` (a multiple of the device's
    /// minUniformBufferOffsetAlignment).
    pub fn uniform_range(self, name: &str, buffer: &Buffer, offset: u64, range: u64) -> Self {
        let what = What::Uniform(buffer.raw, offset, range);
        self.push(
            name,
            what,
            Tracked::Buffer(buffer.raw),
            Usage::Read,
            &buffer.name,
        )
    }

    /// A buffer of addresses, read as a storage buffer; each buffer it points to needs a
    /// declared access ([`Bindings::reaches`]).
    pub fn addresses(self, name: &str, table: &AddressTable) -> Self {
        let mut b = self.buffer(name, &table.buffer, Usage::Read);
        b.entries.last_mut().expect("just pushed").addresses = table.targets.clone();
        b
    }

    /// Declares how the pass uses a buffer it reaches through an address.
    pub fn reaches(mut self, buffer: &Buffer, usage: Usage) -> Self {
        self.reached.push((buffer.raw, buffer.name.clone(), usage));
        self
    }

    /// Applies `f` with the value, when there is one (an optional volume).
    pub fn with<T>(self, value: Option<T>, f: impl FnOnce(Self, T) -> Self) -> Self {
        match value {
            Some(v) => f(self, v),
            None => self,
        }
    }

    fn entry(&self, name: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.name == name)
    }
}

/// The program a pass runs.
pub enum Program<'a> {
    Compute(&'a str),
    Graphics(GraphicsDesc<'a>),
}

/// A descriptor set shared by many passes (the scene's uniforms and buffers, each material's
/// textures), made once from its own table. `instances` sets of one layout: the materials have
/// one each.
pub struct SharedSet {
    /// The set index the shaders declare it at.
    pub index: u32,
    pub layout: SetLayout,
    pub sets: Vec<vk::DescriptorSet>,
    tables: Vec<Bindings>,
    _pool: DescriptorPool,
}

impl SharedSet {
    /// Sets of the tables' bindings at set `index`, laid out as every compiled shader that
    /// declares them there does (they must agree on the binding and the type).
    pub fn new(
        ctx: &Arc<Context>,
        what: &str,
        index: u32,
        tables: Vec<Bindings>,
    ) -> VkResult<SharedSet> {
        let err = |problem: String| VkError::Interface {
            what: what.into(),
            problem,
        };
        let first = tables.first().ok_or_else(|| err("no table".into()))?;
        let all = super::reflect::all_interfaces();
        let mut bindings: Vec<LayoutBinding> = Vec::new();
        for e in &first.entries {
            let mut found: Option<LayoutBinding> = None;
            for (shader, i) in all.iter() {
                let Some(b) = i.binding(index, &e.name) else {
                    continue;
                };
                match &mut found {
                    None => {
                        found = Some(LayoutBinding {
                            binding: b.binding,
                            name: b.name.clone(),
                            ty: b.ty,
                            stages: i.stage,
                        })
                    }
                    Some(f) if f.binding == b.binding && f.ty == b.ty => f.stages |= i.stage,
                    Some(f) => {
                        return Err(err(format!(
                            "{shader} declares {:?} at binding {} ({:?}), others at {} ({:?})",
                            e.name, b.binding, b.ty, f.binding, f.ty
                        )))
                    }
                }
            }
            let found = found
                .ok_or_else(|| err(format!("no shader declares {:?} in set {index}", e.name)))?;
            if found.ty != e.what.ty() {
                return Err(err(format!(
                    "{:?} is {:?} in the shaders, {:?} in the table",
                    e.name,
                    found.ty,
                    e.what.ty()
                )));
            }
            bindings.push(found);
        }
        let layout = SetLayout::new(ctx, bindings)?;
        let layouts: Vec<&SetLayout> = tables.iter().map(|_| &layout).collect();
        let pool = DescriptorPool::for_layouts(ctx, &layouts)?;
        let mut sets = Vec::new();
        for t in &tables {
            let set = pool.allocate(&layout)?;
            write(ctx, set, &layout, t, what)?;
            sets.push(set);
        }
        Ok(SharedSet {
            index,
            layout,
            sets,
            tables,
            _pool: pool,
        })
    }
}

/// Writes each binding of `layout` from the table entry of its name.
fn write(
    ctx: &Context,
    set: vk::DescriptorSet,
    layout: &SetLayout,
    table: &Bindings,
    what: &str,
) -> VkResult<()> {
    let mut found = Vec::new();
    for b in &layout.bindings {
        let e = table.entry(&b.name).ok_or_else(|| VkError::Interface {
            what: what.into(),
            problem: format!("the table binds nothing to {:?}", b.name),
        })?;
        found.push((b.binding, e.what));
    }
    let infos: Vec<([vk::DescriptorBufferInfo; 1], [vk::DescriptorImageInfo; 1])> = found
        .iter()
        .map(|(_, w)| {
            let buffer = |raw, offset, range| vk::DescriptorBufferInfo {
                buffer: raw,
                offset,
                range,
            };
            let image = |view, sampler, layout| vk::DescriptorImageInfo {
                sampler,
                image_view: view,
                image_layout: layout,
            };
            match *w {
                What::StorageBuffer(b) => ([buffer(b, 0, vk::WHOLE_SIZE)], Default::default()),
                What::Uniform(b, offset, range) => ([buffer(b, offset, range)], Default::default()),
                What::StorageImage(v) => (
                    Default::default(),
                    [image(v, vk::Sampler::null(), vk::ImageLayout::GENERAL)],
                ),
                What::Sampled(v, s) => (
                    Default::default(),
                    [image(v, s, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)],
                ),
            }
        })
        .collect();
    let writes: Vec<_> = found
        .iter()
        .zip(&infos)
        .map(|((binding, w), (buffer, image))| {
            let write = vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(*binding)
                .descriptor_type(w.ty());
            match w {
                What::StorageBuffer(_) | What::Uniform(..) => write.buffer_info(buffer),
                _ => write.image_info(image),
            }
        })
        .collect();
    unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
    Ok(())
}

/// A binding the pass's shaders use, merged over their stages.
#[derive(Clone, Debug)]
struct Used {
    set: u32,
    binding: u32,
    name: String,
    ty: vk::DescriptorType,
    stages: vk::ShaderStageFlags,
    reads: bool,
    writes: bool,
}

/// A pipeline with its own descriptor sets, made from its binding table, and the accesses that
/// table declares. `instances` tables of one layout give sets the pass chooses between when it
/// records (a mip level each).
pub struct Pass {
    pub name: String,
    pub pipeline: Pipeline,
    graphics: bool,
    used: Vec<Used>,
    /// The pass's own set layouts, by set index.
    own: Vec<(u32, SetLayout)>,
    /// Per instance: its own sets, in the order of `own`.
    sets: Vec<Vec<vk::DescriptorSet>>,
    /// Per instance: the accesses to declare (own tables, addresses reached, shared sets).
    accesses: Vec<Vec<(Tracked, Access)>>,
    _empty: Vec<SetLayout>,
    /// None when the pass has no sets of its own (it draws with shared ones only).
    _pool: Option<DescriptorPool>,
}

impl Pass {
    pub fn new(
        ctx: &Arc<Context>,
        program: Program,
        shared: &[&SharedSet],
        tables: Vec<Bindings>,
        push_size: u32,
    ) -> VkResult<Pass> {
        let (name, stage_names): (String, Vec<&str>) = match &program {
            Program::Compute(s) => (s.to_string(), vec![*s]),
            Program::Graphics(d) => (d.name.into(), d.shaders.iter().map(|(_, s)| *s).collect()),
        };
        let err = |problem: String| VkError::Interface {
            what: name.clone(),
            problem,
        };
        let shaders = stage_names
            .iter()
            .map(|s| Shader::load(s))
            .collect::<VkResult<Vec<_>>>()?;
        let used = merge_stages(&shaders).map_err(&err)?;
        let shared_at = |index: u32| shared.iter().find(|s| s.index == index);
        let mut indices: Vec<u32> = used
            .iter()
            .map(|u| u.set)
            .filter(|&i| shared_at(i).is_none())
            .collect();
        indices.sort();
        indices.dedup();
        let own = indices
            .iter()
            .map(|&i| {
                let bindings = used
                    .iter()
                    .filter(|u| u.set == i)
                    .map(|u| LayoutBinding {
                        binding: u.binding,
                        name: u.name.clone(),
                        ty: u.ty,
                        stages: u.stages,
                    })
                    .collect();
                Ok((i, SetLayout::new(ctx, bindings)?))
            })
            .collect::<VkResult<Vec<_>>>()?;
        for t in &tables {
            check_table(&used, t, |i| shared_at(i).is_some()).map_err(&err)?;
        }
        let layouts: Vec<&SetLayout> = tables
            .iter()
            .flat_map(|_| own.iter().map(|(_, l)| l))
            .collect();
        let pool = match layouts.is_empty() {
            true => None,
            false => Some(DescriptorPool::for_layouts(ctx, &layouts)?),
        };
        let mut sets = Vec::new();
        for t in &tables {
            let mut instance = Vec::new();
            for (_, layout) in &own {
                let set = pool
                    .as_ref()
                    .expect("a pool for own sets")
                    .allocate(layout)?;
                write(ctx, set, layout, t, &name)?;
                instance.push(set);
            }
            sets.push(instance);
        }

        // Set indices up to the highest: shared, own, or empty where no shader uses one.
        let top = used
            .iter()
            .map(|u| u.set + 1)
            .chain(shared.iter().map(|s| s.index + 1))
            .max()
            .unwrap_or(0);
        let mut empty = Vec::new();
        for i in 0..top {
            if shared_at(i).is_none() && !indices.contains(&i) {
                empty.push(SetLayout::empty(ctx)?);
            }
        }
        let mut empties = empty.iter();
        let set_layouts: Vec<&SetLayout> = (0..top)
            .map(
                |i| match (shared_at(i), own.iter().find(|(k, _)| *k == i)) {
                    (Some(s), _) => &s.layout,
                    (None, Some((_, l))) => l,
                    (None, None) => empties.next().expect("an empty layout per gap"),
                },
            )
            .collect();
        let pipeline = match &program {
            Program::Compute(_) => pipeline::compute(ctx, &shaders[0], &set_layouts, push_size)?,
            Program::Graphics(d) => pipeline::graphics(ctx, d, &shaders, &set_layouts, push_size)?,
        };
        let graphics = matches!(program, Program::Graphics(_));
        let accesses = tables
            .iter()
            .map(|t| accesses(&used, t, shared, graphics))
            .collect::<Result<Vec<_>, String>>()
            .map_err(&err)?;
        Ok(Pass {
            name,
            pipeline,
            graphics,
            used,
            own,
            sets,
            accesses,
            _empty: empty,
            _pool: pool,
        })
    }

    /// A compute pass of one table.
    pub fn compute(
        ctx: &Arc<Context>,
        shader: &str,
        shared: &[&SharedSet],
        table: Bindings,
        push_size: u32,
    ) -> VkResult<Pass> {
        Pass::new(
            ctx,
            Program::Compute(shader),
            shared,
            vec![table],
            push_size,
        )
    }

    /// Points instance `instance`'s sets at the resources of a new table of the same shape (a
    /// resized frame's images). No submitted work may be using the sets.
    pub fn rebind(
        &mut self,
        ctx: &Context,
        instance: usize,
        table: Bindings,
        shared: &[&SharedSet],
    ) -> VkResult<()> {
        let err = |problem: String| VkError::Interface {
            what: self.name.clone(),
            problem,
        };
        check_table(&self.used, &table, |i| shared.iter().any(|s| s.index == i)).map_err(&err)?;
        for ((_, layout), &set) in self.own.iter().zip(&self.sets[instance]) {
            write(ctx, set, layout, &table, &self.name)?;
        }
        self.accesses[instance] =
            accesses(&self.used, &table, shared, self.graphics).map_err(&err)?;
        Ok(())
    }

    /// Declares instance `instance`'s accesses on a graph pass.
    pub fn declare<'g, 'a, 'r>(
        &self,
        mut pass: PassBuilder<'g, 'a, 'r>,
        instance: usize,
    ) -> PassBuilder<'g, 'a, 'r> {
        for &(t, a) in &self.accesses[instance] {
            pass = pass.tracked(t, a);
        }
        pass
    }

    /// Records graph pass `name` as one compute dispatch of instance 0: its declared accesses,
    /// the shared sets given, `push` (when not empty) and `groups` work groups.
    pub fn record_dispatch(
        &self,
        ctx: &Context,
        g: &mut Graph,
        name: &str,
        shared: &[(u32, vk::DescriptorSet)],
        push: &[u8],
        groups: [u32; 3],
    ) {
        let d = &ctx.device;
        self.declare(g.pass(name), 0).record(|cmd| unsafe {
            self.bind(d, cmd, shared, 0);
            if !push.is_empty() {
                self.pipeline.push(d, cmd, push);
            }
            d.cmd_dispatch(cmd, groups[0], groups[1], groups[2]);
        });
    }

    /// Binds the pipeline, the shared sets given and instance `instance`'s own sets.
    ///
    /// # Safety
    /// `cmd` is recording; each shared set is one the pass was made with.
    pub unsafe fn bind(
        &self,
        d: &ash::Device,
        cmd: vk::CommandBuffer,
        shared: &[(u32, vk::DescriptorSet)],
        instance: usize,
    ) {
        self.pipeline.bind(d, cmd);
        for &(index, set) in shared {
            self.pipeline.bind_sets(d, cmd, index, &[set]);
        }
        for ((index, _), &set) in self.own.iter().zip(&self.sets[instance]) {
            self.pipeline.bind_sets(d, cmd, *index, &[set]);
        }
    }
}

/// The bindings the shaders use, one per (set, binding), with the stages that use them.
fn merge_stages(shaders: &[Shader]) -> Result<Vec<Used>, String> {
    let mut used: Vec<Used> = Vec::new();
    for s in shaders {
        for b in &s.interface.bindings {
            if b.count != 1 {
                return Err(format!(
                    "{}: {:?} is an array of descriptors",
                    s.name, b.name
                ));
            }
            match used
                .iter_mut()
                .find(|u| u.set == b.set && u.binding == b.binding)
            {
                Some(u) if u.name == b.name && u.ty == b.ty => {
                    u.stages |= s.interface.stage;
                    u.reads |= b.reads;
                    u.writes |= b.writes;
                }
                Some(u) => {
                    return Err(format!(
                        "set {} binding {} is {:?} in one stage, {:?} in {}",
                        b.set, b.binding, u.name, b.name, s.name
                    ))
                }
                None => used.push(Used {
                    set: b.set,
                    binding: b.binding,
                    name: b.name.clone(),
                    ty: b.ty,
                    stages: s.interface.stage,
                    reads: b.reads,
                    writes: b.writes,
                }),
            }
        }
    }
    Ok(used)
}

/// The table against the shaders: each binding they use in the pass's own sets has an entry of
/// its type whose declared use is the shader's (a `readonly` binding read, a `writeonly` one
/// written, one without either both), and each buffer reached through an address table they
/// use has a declared access.
fn check_table(used: &[Used], t: &Bindings, shared: impl Fn(u32) -> bool) -> Result<(), String> {
    for (i, e) in t.entries.iter().enumerate() {
        if t.entries[..i].iter().any(|o| o.name == e.name) {
            return Err(format!("the table binds {:?} twice", e.name));
        }
    }
    for u in used.iter().filter(|u| !shared(u.set)) {
        let e = t.entry(&u.name).ok_or_else(|| {
            format!(
                "its shaders use {:?} (set {}, binding {}), which the table does not bind",
                u.name, u.set, u.binding
            )
        })?;
        if e.what.ty() != u.ty {
            return Err(format!(
                "{:?} is {:?} in the shaders, {:?} ({}) in the table",
                u.name,
                u.ty,
                e.what.ty(),
                e.resource
            ));
        }
        if (e.usage.reads(), e.usage.writes()) != (u.reads, u.writes) {
            return Err(format!(
                "the table declares {:?} ({}) {:?}, the shaders {}",
                u.name,
                e.resource,
                e.usage,
                match (u.reads, u.writes) {
                    (true, false) => "only read it (readonly)",
                    (false, true) => "only write it (writeonly)",
                    _ => "read and write it (no qualifier)",
                }
            ));
        }
        for (buffer, target) in &e.addresses {
            if !t.reached.iter().any(|(b, _, _)| b == buffer) {
                return Err(format!(
                    "its shaders reach {target} through the addresses in {:?} ({}), and the \
                     table declares no access of it (Bindings::reaches)",
                    u.name, e.resource
                ));
            }
        }
    }
    Ok(())
}

/// The graph access of a use, in a compute or a graphics pass.
fn access(what: What, usage: Usage, graphics: bool) -> Access {
    match (what, graphics, usage) {
        (What::Sampled(..), false, _) => Access::ComputeSampled,
        (What::Sampled(..), true, _) => Access::FragmentSampled,
        (What::Uniform(..), false, _) => Access::ComputeStorageRead,
        (What::Uniform(..), true, _) => Access::GraphicsBufferRead,
        (_, false, Usage::Read) => Access::ComputeStorageRead,
        (_, false, Usage::Write) => Access::ComputeStorageWrite,
        (_, false, Usage::ReadWrite) => Access::ComputeStorageReadWrite,
        (_, false, Usage::Indirect) => Access::ComputeIndirectRead,
        (_, true, Usage::Read) => Access::GraphicsBufferRead,
        (_, true, _) => Access::FragmentStorageReadWrite,
    }
}

/// What one instance declares: the entries its shaders use (a resource bound twice, say two
/// mip levels of one image, once with both uses), the buffers reached through addresses, and
/// the shared sets' entries the shaders use.
fn accesses(
    used: &[Used],
    t: &Bindings,
    shared: &[&SharedSet],
    graphics: bool,
) -> Result<Vec<(Tracked, Access)>, String> {
    let mut uses: Vec<(Tracked, What, Usage)> = Vec::new();
    let mut add = |tracked: Tracked, what: What, usage: Usage| -> Result<(), String> {
        match uses.iter_mut().find(|(t, _, _)| *t == tracked) {
            Some((_, w, u)) => {
                if std::mem::discriminant(w) != std::mem::discriminant(&what) {
                    return Err(format!(
                        "one resource is bound as {:?} and as {:?}",
                        w.ty(),
                        what.ty()
                    ));
                }
                *u = u.and(usage);
            }
            None => uses.push((tracked, what, usage)),
        }
        Ok(())
    };
    for u in used {
        match shared.iter().find(|s| s.index == u.set) {
            Some(s) => {
                for table in &s.tables {
                    if let Some(e) = table.entry(&u.name) {
                        add(e.tracked, e.what, e.usage)?;
                    }
                }
            }
            None => {
                let e = t.entry(&u.name).expect("checked");
                add(e.tracked, e.what, e.usage)?;
                for (buffer, _) in &e.addresses {
                    let (_, _, usage) = t
                        .reached
                        .iter()
                        .find(|(b, _, _)| b == buffer)
                        .expect("checked");
                    add(
                        Tracked::Buffer(*buffer),
                        What::StorageBuffer(*buffer),
                        *usage,
                    )?;
                }
            }
        }
    }
    Ok(uses
        .into_iter()
        .map(|(t, w, u)| (t, access(w, u, graphics)))
        .collect())
}
