//! Compiles the previewer's GLSL shaders (`src/preview/shaders/`) to SPIR-V with naga, so
//! that no system shader compiler is needed (DESIGN.md §3). A line `//INCLUDE name` is
//! replaced by that file of the same folder (naga's GLSL front end has no `#include`).

use naga::back::spv;
use naga::front::glsl;
use naga::valid::{Capabilities, ValidationFlags, Validator};
use naga::ShaderStage;
use std::path::Path;

const SHADERS: &[&str] = &[
    "gbuffer.vert",
    "gbuffer.frag",
    "splat.vert",
    "splat.frag",
    "disk.vert",
    "disk.frag",
    "resolve.vert",
    "resolve.frag",
];

fn main() {
    let dir = Path::new("src/preview/shaders");
    println!("cargo:rerun-if-changed={}", dir.display());
    let out = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    for name in SHADERS {
        let source = expand(dir, name);
        let stage = if name.ends_with(".vert") {
            ShaderStage::Vertex
        } else {
            ShaderStage::Fragment
        };
        let module = glsl::Frontend::default()
            .parse(&glsl::Options::from(stage), &source)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
        let info = Validator::new(ValidationFlags::all(), Capabilities::IMMEDIATES)
            .validate(&module)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
        let options = spv::Options {
            // GLSL for Vulkan already has Vulkan's clip space: no y flip.
            flags: spv::WriterFlags::empty(),
            ..Default::default()
        };
        let pipeline = spv::PipelineOptions {
            shader_stage: stage,
            entry_point: "main".into(),
        };
        let words = spv::write_vec(&module, &info, &options, Some(&pipeline))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        let target = Path::new(&out).join(format!("{name}.spv"));
        std::fs::write(&target, bytes).unwrap_or_else(|e| panic!("{}: {e}", target.display()));
    }
}

fn expand(dir: &Path, name: &str) -> String {
    let read =
        |n: &str| std::fs::read_to_string(dir.join(n)).unwrap_or_else(|e| panic!("{n}: {e}"));
    read(name)
        .lines()
        .map(|line| match line.trim().strip_prefix("//INCLUDE ") {
            Some(inc) => read(inc.trim()),
            None => line.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
}
