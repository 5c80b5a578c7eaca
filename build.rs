//! Compiles every shader in glsl/ to SPIR-V with shaderc; the binary embeds the results.
//! `#include "file.glsl"` resolves relative to glsl/. A shader error fails the build with the
//! file and line.

use std::path::{Path, PathBuf};

fn main() {
    let glsl = Path::new("glsl");
    println!("cargo:rerun-if-changed=glsl");
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    let compiler = shaderc::Compiler::new().expect("shaderc: cannot create a compiler");

    let mut entries: Vec<PathBuf> = std::fs::read_dir(glsl)
        .expect("glsl/ is missing")
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();

    let mut table = String::from("/// (file name, SPIR-V bytes) of every shader in glsl/.\n");
    table.push_str("pub static SPIRV: &[(&str, &[u8])] = &[\n");
    let mut failures = Vec::new();
    for path in entries {
        println!("cargo:rerun-if-changed={}", path.display());
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let kind = match path.extension().and_then(|e| e.to_str()) {
            Some("vert") => shaderc::ShaderKind::Vertex,
            Some("frag") => shaderc::ShaderKind::Fragment,
            Some("geom") => shaderc::ShaderKind::Geometry,
            Some("comp") => shaderc::ShaderKind::Compute,
            _ => continue, // includes (.glsl) are compiled as part of the shaders that use them
        };
        let source = std::fs::read_to_string(&path).unwrap();
        // A line `// variants: A B` also compiles the shader with each name #defined, as
        // "file:A", "file:B" (e.g. the paper-faithful path beside the default one).
        let mut variants = vec![None];
        for line in source.lines().take(8) {
            if let Some(list) = line.trim().strip_prefix("// variants:") {
                variants.extend(list.split_whitespace().map(|v| Some(v.to_string())));
            }
        }
        for variant in variants {
            let mut options = shaderc::CompileOptions::new().unwrap();
            // SPIR-V 1.5: 1.6 would declare LocalSizeId, which needs the maintenance4 feature.
            options.set_target_env(
                shaderc::TargetEnv::Vulkan,
                shaderc::EnvVersion::Vulkan1_2 as u32,
            );
            options.set_optimization_level(shaderc::OptimizationLevel::Performance);
            options.set_generate_debug_info();
            if let Some(v) = &variant {
                options.add_macro_definition(v, Some("1"));
            }
            options.set_include_callback(|requested, _ty, requester, _depth| {
                let file = glsl.join(requested);
                match std::fs::read_to_string(&file) {
                    Ok(content) => Ok(shaderc::ResolvedInclude {
                        resolved_name: file.display().to_string(),
                        content,
                    }),
                    Err(e) => Err(format!(
                        "{requester}: cannot include {}: {e}",
                        file.display()
                    )),
                }
            });
            let key = match &variant {
                Some(v) => format!("{name}:{v}"),
                None => name.clone(),
            };
            let display = path.display().to_string();
            match compiler.compile_into_spirv(&source, kind, &display, "main", Some(&options)) {
                Ok(artifact) => {
                    let spv = out_dir.join(format!("{}.spv", key.replace(':', ".")));
                    std::fs::write(&spv, artifact.as_binary_u8()).unwrap();
                    table.push_str(&format!(
                        "    ({key:?}, include_bytes!({:?})),\n",
                        spv.display().to_string()
                    ));
                }
                Err(e) => failures.push(match &variant {
                    Some(v) => format!("(with {v} defined) {e}"),
                    None => e.to_string(),
                }),
            }
        }
    }
    if !failures.is_empty() {
        // shaderc's messages read "glsl/file.frag:LINE: error: ..."
        for f in &failures {
            eprintln!("{f}");
        }
        panic!("shader compilation failed:\n{}", failures.join("\n"));
    }
    table.push_str("];\n");
    std::fs::write(out_dir.join("shaders.rs"), table).unwrap();
}
