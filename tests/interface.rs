//! A pass's binding table against its shaders' SPIR-V: a table that lacks a binding the shader
//! uses, binds another type, declares a read where the shader writes, pushes another number of
//! bytes, or reaches a buffer through an address table without declaring its access, fails
//! when the pass is made, with a message that names the pass and what is wrong.

mod gpu;
use gpu::context;
use gpu_allocator::MemoryLocation;
use voxgi::vk::{
    vk, AddressTable, Bindings, Buffer, Context, Image, ImageDesc, Pass, Usage, VkError,
};

fn words(ctx: &std::sync::Arc<Context>, name: &str) -> Buffer {
    Buffer::new(
        ctx,
        name,
        256,
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
        MemoryLocation::GpuOnly,
    )
    .unwrap()
}

fn words_buffer(ctx: &std::sync::Arc<Context>) -> Buffer {
    words(ctx, "some buffer")
}

fn problem(r: Result<Pass, VkError>) -> String {
    match r {
        Ok(_) => panic!("the pass was made"),
        Err(e) => e.to_string(),
    }
}

fn volume(ctx: &std::sync::Arc<Context>, name: &str, format: vk::Format) -> Image {
    let usage = vk::ImageUsageFlags::STORAGE;
    Image::new(ctx, name, ImageDesc::d3(format, 4, usage)).unwrap()
}

#[test]
fn a_buffer_reached_by_address_without_a_declared_access_is_caught() {
    let ctx = context();
    let stats = ctx.stats.clone();
    {
        let (albedo, normal) = (words(&ctx, "albedo words"), words(&ctx, "normal words"));
        let list = words(&ctx, "list");
        let usage = vk::BufferUsageFlags::UNIFORM_BUFFER;
        let frame = Buffer::new(&ctx, "frame", 4096, usage, MemoryLocation::GpuOnly).unwrap();
        let s = AddressTable::new(&ctx, "static addresses", &[Some(&albedo), Some(&normal)]);
        let d = AddressTable::new(&ctx, "dynamic addresses", &[]);
        let (s, d) = (s.unwrap(), d.unwrap());
        // voxel_list.comp reaches the default's words through the tables at "StaticWords"
        // and "DynamicWords" (glsl/voxel_data.glsl).
        let table = || {
            Bindings::new()
                .uniform("frame", &frame)
                .buffer("VoxelList", &list, Usage::ReadWrite)
                .addresses("StaticWords", &s)
                .addresses("DynamicWords", &d)
        };
        let both = table()
            .reaches(&albedo, Usage::Read)
            .reaches(&normal, Usage::Read);
        let made = Pass::compute(&ctx, "voxel_list.comp", &[], both, 0);
        assert!(made.is_ok(), "{:?}", made.err());
        let one = table().reaches(&albedo, Usage::Read);
        let p = problem(Pass::compute(&ctx, "voxel_list.comp", &[], one, 0));
        assert!(
            p.contains("voxel_list.comp") && p.contains("normal words"),
            "{p}"
        );
    }
    drop(ctx);
    assert_eq!(stats.count(), 0, "{:#?}", stats.messages());
}

#[test]
fn a_table_that_disagrees_with_its_shader_is_caught() {
    let ctx = context();
    let stats = ctx.stats.clone();
    {
        let texels = vk::Format::R8G8B8A8_UNORM;
        let albedo = volume(&ctx, "albedo", texels);
        let normal = volume(&ctx, "normal", texels);
        let emission = volume(&ctx, "emission", texels);
        let flag = volume(&ctx, "flag", vk::Format::R8_UNORM);
        let buffer = words_buffer(&ctx);
        // clear_dynamic.comp reads and writes the paper's albedo, writes its normals and
        // emission, and reads its flags.
        let three = || {
            Bindings::new()
                .image("paper_albedo", &albedo, Usage::ReadWrite)
                .image("paper_normal", &normal, Usage::Write)
                .image("paper_emission", &emission, Usage::Write)
        };
        let ok = || three().image("paper_flag", &flag, Usage::Read);
        // A binding the shader uses and the table lacks.
        let p = problem(Pass::compute(&ctx, "clear_dynamic.comp", &[], three(), 4));
        assert!(
            p.contains("paper_flag") && p.contains("does not bind"),
            "{p}"
        );
        // Declared written where the shader only reads (readonly).
        let written = three().image("paper_flag", &flag, Usage::ReadWrite);
        let p = problem(Pass::compute(&ctx, "clear_dynamic.comp", &[], written, 4));
        assert!(p.contains("readonly"), "{p}");
        // Another type: a storage buffer where the shader has a storage image.
        let other = three().buffer("paper_flag", &buffer, Usage::Read);
        let p = problem(Pass::compute(&ctx, "clear_dynamic.comp", &[], other, 4));
        assert!(p.contains("STORAGE_BUFFER"), "{p}");
        // Push constants of another size.
        let p = problem(Pass::compute(&ctx, "clear_dynamic.comp", &[], ok(), 8));
        assert!(p.contains("push constants take 4 bytes"), "{p}");
        // A binding bound twice.
        let twice = ok().image("paper_flag", &flag, Usage::Read);
        let p = problem(Pass::compute(&ctx, "clear_dynamic.comp", &[], twice, 4));
        assert!(p.contains("twice"), "{p}");
        assert!(Pass::compute(&ctx, "clear_dynamic.comp", &[], ok(), 4).is_ok());
    }
    drop(ctx);
    assert_eq!(stats.count(), 0, "{:#?}", stats.messages());
}
