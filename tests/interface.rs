//! A pass's binding table against its shaders' SPIR-V: a table that lacks a binding the shader
//! uses, binds another type, declares a read where the shader writes, pushes another number of
//! bytes, or reaches a buffer through an address table without declaring its access, fails
//! when the pass is made, with a message that names the pass and what is wrong.

mod gpu;
use gpu::context;
use gpu_allocator::MemoryLocation;
use voxgi::vk::{vk, AddressTable, Bindings, Buffer, Context, Pass, Usage, VkError};

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

fn problem(r: Result<Pass, VkError>) -> String {
    match r {
        Ok(_) => panic!("the pass was made"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_buffer_reached_by_address_without_a_declared_access_is_caught() {
    let ctx = context();
    let stats = ctx.stats.clone();
    {
        let (albedo, normal) = (words(&ctx, "albedo words"), words(&ctx, "normal words"));
        let table =
            AddressTable::new(&ctx, "word addresses", &[Some(&albedo), Some(&normal)]).unwrap();
        // clear_dynamic.comp reaches the paper's words through the table at "PaperWords".
        let both = Bindings::new()
            .addresses("PaperWords", &table)
            .reaches(&albedo, Usage::ReadWrite)
            .reaches(&normal, Usage::ReadWrite);
        assert!(Pass::compute(&ctx, "clear_dynamic.comp", &[], both, 4).is_ok());
        let one = Bindings::new()
            .addresses("PaperWords", &table)
            .reaches(&albedo, Usage::ReadWrite);
        let p = problem(Pass::compute(&ctx, "clear_dynamic.comp", &[], one, 4));
        assert!(
            p.contains("clear_dynamic.comp") && p.contains("normal words"),
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
        let buffer = words(&ctx, "some buffer");
        let table = AddressTable::new(&ctx, "word addresses", &[Some(&buffer)]).unwrap();
        let ok = || {
            Bindings::new()
                .addresses("PaperWords", &table)
                .reaches(&buffer, Usage::ReadWrite)
        };
        // A binding the shader uses and the table lacks.
        let p = problem(Pass::compute(
            &ctx,
            "clear_dynamic.comp",
            &[],
            Bindings::new(),
            4,
        ));
        assert!(
            p.contains("PaperWords") && p.contains("does not bind"),
            "{p}"
        );
        // Declared written where the shader only reads (readonly).
        let written = Bindings::new()
            .buffer("PaperWords", &table.buffer, Usage::ReadWrite)
            .reaches(&buffer, Usage::ReadWrite);
        let p = problem(Pass::compute(&ctx, "clear_dynamic.comp", &[], written, 4));
        assert!(p.contains("readonly"), "{p}");
        // Another type: a uniform buffer where the shader has a storage buffer.
        let uniform = Bindings::new()
            .uniform("PaperWords", &table.buffer)
            .reaches(&buffer, Usage::ReadWrite);
        let p = problem(Pass::compute(&ctx, "clear_dynamic.comp", &[], uniform, 4));
        assert!(p.contains("UNIFORM_BUFFER"), "{p}");
        // Push constants of another size.
        let p = problem(Pass::compute(&ctx, "clear_dynamic.comp", &[], ok(), 8));
        assert!(p.contains("push constants take 4 bytes"), "{p}");
        // A binding bound twice.
        let twice = ok().buffer("PaperWords", &buffer, Usage::Read);
        let p = problem(Pass::compute(&ctx, "clear_dynamic.comp", &[], twice, 4));
        assert!(p.contains("twice"), "{p}");
        assert!(Pass::compute(&ctx, "clear_dynamic.comp", &[], ok(), 4).is_ok());
    }
    drop(ctx);
    assert_eq!(stats.count(), 0, "{:#?}", stats.messages());
}
