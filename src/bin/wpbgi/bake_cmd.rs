//! `wpbgi bake` and `wpbgi inspect`.

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use serde_json::{json, Value};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;
use wpbgi::bake::bounce::kept::beside;
use wpbgi::bake::bounce::BounceSettings;
use wpbgi::bake::bounce::TransportHandoff;
use wpbgi::bake::{bake_with_transport, BakeSettings, Quality};
use wpbgi::cache::store::BakedCache;

/// `--quality`: a bake preset, by its name; `--help` gives each one's surfels and light
/// samples, read from the library's presets.
#[derive(Clone, Copy, Debug)]
pub enum QualityArg {
    Draft,
    Preview,
    Final,
    Ultra,
}

impl ValueEnum for QualityArg {
    fn value_variants<'a>() -> &'a [Self] {
        &[
            QualityArg::Draft,
            QualityArg::Preview,
            QualityArg::Final,
            QualityArg::Ultra,
        ]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        let q = self.quality();
        Some(clap::builder::PossibleValue::new(q.name()).help(format!(
            "{} surfels, {} light samples each",
            q.points(),
            q.light_samples()
        )))
    }
}

impl QualityArg {
    /// The argument that names `q`.
    pub fn of(q: Quality) -> QualityArg {
        match q {
            Quality::Draft => QualityArg::Draft,
            Quality::Preview => QualityArg::Preview,
            Quality::Final => QualityArg::Final,
            Quality::Ultra => QualityArg::Ultra,
        }
    }

    pub fn quality(self) -> Quality {
        match self {
            QualityArg::Draft => Quality::Draft,
            QualityArg::Preview => Quality::Preview,
            QualityArg::Final => Quality::Final,
            QualityArg::Ultra => Quality::Ultra,
        }
    }
}

#[derive(Args)]
pub struct BakeArgs {
    /// The scene (.gltf, .glb, .usd, .usda, .usdc or .usdz).
    scene: PathBuf,
    /// The cache to write (.wpc). Written atomically: an interrupted bake leaves the previous
    /// file untouched.
    #[arg(short, long)]
    output: PathBuf,
    /// Quality preset: surfel count and light samples per surfel.
    #[arg(long, value_enum, default_value_t = QualityArg::of(Quality::default()))]
    quality: QualityArg,
    /// Number of surfels (overrides the preset).
    #[arg(long)]
    points: Option<usize>,
    /// Emitter samples per surfel (overrides the preset).
    #[arg(long)]
    light_samples: Option<u32>,
    /// Relative wavelet threshold: coefficients below this fraction of their function's norm
    /// are dropped.
    #[arg(long, default_value_t = BakeSettings::default().tau)]
    threshold: f32,
    /// Tree level where the hierarchical coding switches from stored averages to details
    /// (default: three levels above the leaves).
    #[arg(long)]
    split_level: Option<u32>,
    /// Seed of the random streams.
    #[arg(long, default_value_t = BakeSettings::default().seed)]
    seed: u64,
    /// With many point and spot lights (Lightcuts): the largest cut per surfel, in clusters.
    #[arg(long, default_value_t = BakeSettings::default().max_cut)]
    max_cut: usize,
    /// Indirect bounces after the direct light: a number (0: a direct-only cache), or `auto`:
    /// until a bounce adds less than 3 % of the light (at most 30), then the bounces left at
    /// once, as the geometric tail of the last (r/(1 − r) times it, r the ratio of the last
    /// two bounces' light, for red, green and blue apart).
    #[arg(long, default_value_t = BakeSettings::default().bounces, value_parser = parse_bounces)]
    bounces: BounceSettings,
    /// Memory (MB) the bounces may keep their recorded light transport in: the first bounce
    /// records which senders every surfel sees and how, and later bounces replay it against
    /// the new light. Surfels past it gather again in every bounce (slower, same cache).
    /// Default: 40 % of the machine's memory.
    #[arg(long, value_name = "MB")]
    transport_memory: Option<u64>,
    /// Also write the bounces' recorded light transport beside the cache (OUTPUT.transport,
    /// several times the cache's size): `wpbgi relight` then re-solves the bounces for an
    /// edited reflectance, tint, transmittance or emission from it instead of baking again
    /// (docs/relight.md). Only the groups kept in --transport-memory are written.
    #[arg(long)]
    keep_transport: bool,
    /// About one surfel in N gathers indirect light in each bounce; the others blend the
    /// light of their nearest gathering neighbours on the same surface (indirect light varies
    /// slowly, and the final render gathers it again). 1: every surfel gathers.
    #[arg(long, value_name = "N", default_value_t = BakeSettings::default().bounces.receiver_stride,
          value_parser = clap::value_parser!(u32).range(1..))]
    receiver_stride: u32,
    /// MATERIAL=FACTOR: that material's surfaces get FACTOR times the surfels per unit area of
    /// the others (the total stays --points). Glass that casts caustics sharpens them when
    /// finer (e.g. `glass=2`); a material that matters little can be made coarser (`0.5`).
    /// Repeatable.
    #[arg(long, value_name = "MATERIAL=FACTOR", value_parser = parse_density)]
    surfel_density: Vec<(String, f32)>,
    /// Report the plan, progress and summary as JSON lines on standard output (events
    /// "plan", "progress" and "done"; a failure as {"error": ..., "exit": ...}).
    #[arg(long)]
    pub(crate) json: bool,
}

fn parse_density(s: &str) -> Result<(String, f32), String> {
    let (name, factor) = s
        .rsplit_once('=')
        .ok_or_else(|| format!("expected MATERIAL=FACTOR, got \"{s}\""))?;
    // Its range is the settings' to refuse (BakeSettings::validate).
    factor
        .parse::<f32>()
        .map(|w| (name.to_string(), w))
        .map_err(|_| format!("the factor of \"{name}\" must be a number, got \"{factor}\""))
}

pub(crate) fn parse_bounces(s: &str) -> Result<BounceSettings, String> {
    if s == "auto" {
        return Ok(BounceSettings::auto());
    }
    s.parse::<u32>()
        .map(BounceSettings::exactly)
        .map_err(|_| format!("expected a number of bounces or `auto`, got \"{s}\""))
}

#[derive(Args)]
pub struct InspectArgs {
    /// The cache (.wpc).
    cache: PathBuf,
    /// Print the report as one JSON document on standard output (a failure as
    /// {"error": ..., "exit": ...}).
    #[arg(long)]
    pub(crate) json: bool,
    /// Also write the surfels as a PLY point cloud with normals and colours.
    #[arg(long)]
    ply: Option<PathBuf>,
    /// Check the cache against this scene and refuse it if it is stale.
    #[arg(long)]
    scene: Option<PathBuf>,
}

fn settings_of(a: &BakeArgs) -> BakeSettings {
    let mut s = BakeSettings::preset(a.quality.quality());
    s.points = a.points.unwrap_or(s.points);
    s.light_samples = a.light_samples.unwrap_or(s.light_samples);
    s.tau = a.threshold;
    s.split_level = a.split_level;
    s.seed = a.seed;
    s.max_cut = a.max_cut;
    s.surfel_density = a.surfel_density.clone();
    s.bounces = BounceSettings {
        transport_budget: a.transport_memory.map(|mb| mb.saturating_mul(1_000_000)),
        receiver_stride: a.receiver_stride,
        ..a.bounces
    };
    s
}

/// One JSON line on standard output, flushed at once (a progress event is read while the
/// bake runs).
fn emit_json(v: Value) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{v}");
    let _ = out.flush();
}

pub fn bake_command(a: BakeArgs) -> Result<()> {
    let start = Instant::now();
    let scene = crate::load_scene(&a.scene)?;
    crate::warn(&scene);
    let settings = settings_of(&a);
    settings.validate()?;
    let mut plan = wpbgi::bake::Plan::new(&scene);
    plan.note_bounces(&settings.bounces);
    if a.json {
        emit_json(json!({"event": "plan", "plan": plan.json, "settings": settings.to_json()}));
    } else {
        say!("bake plan for {}:", a.scene.display());
        say!(
            "  {} surfels, {} light samples each",
            settings.points,
            settings.light_samples
        );
        for m in plan.json["materials"].as_array().into_iter().flatten() {
            let density = settings
                .surfel_density
                .iter()
                .rev()
                .find(|(name, _)| m["name"].as_str() == Some(name.as_str()))
                .map_or(String::new(), |(_, w)| format!(", surfels ×{w}"));
            say!(
                "  material {}: {}, {}{density}",
                m["name"],
                m["model"],
                m["storage"]
            );
        }
        if let Some(b) = plan.json["bounces"].as_str() {
            say!("  indirect bounces: {b}");
        }
        for l in plan.json["left_out"].as_array().into_iter().flatten() {
            say!("  left out: {}", l.as_str().unwrap_or_default());
        }
    }
    let bar = (!a.json).then(|| crate::StagedBar::new("baking"));
    let progress = |stage: &str, f: f32| {
        if a.json {
            emit_json(json!({"event": "progress", "stage": stage, "fraction": f}));
        } else if let Some(b) = &bar {
            b.update(stage, f);
        }
    };
    let transport_path = beside(&a.output);
    crate::interrupt::guard_outputs([a.output.clone(), transport_path.clone()]);
    let mut handoff = TransportHandoff {
        keep: a.keep_transport,
        ..TransportHandoff::default()
    };
    let baked = bake_with_transport(
        &scene,
        &settings,
        &progress,
        crate::interrupt::flag(),
        &mut handoff,
    )?;
    bar.as_ref().map(crate::StagedBar::finish);
    let coefficients = baked.coded.stored_counts().1;
    let t = Instant::now();
    wpbgi::bake::store::save(&a.output, &scene, &baked)?;
    let transport_bytes = match handoff.kept.take() {
        Some(kept) => {
            kept.write(&transport_path).with_context(|| {
                format!(
                    "{} was written, but its transport was not kept",
                    a.output.display()
                )
            })?;
            std::fs::metadata(&transport_path).map_or(0, |m| m.len())
        }
        None => 0,
    };
    // The cache holds what the inputs determine; times and memory are reported here.
    let mut stats = wpbgi::bake::store::cache_stats(&baked);
    let bytes = std::fs::metadata(&a.output).map(|m| m.len()).unwrap_or(0);
    stats["seconds"] = crate::stage_seconds_json(&baked.timings);
    stats["seconds"]["write"] = json!(t.elapsed().as_secs_f64());
    if let Some(r) = &baked.bounces {
        stats["bounces"] = crate::bounces_json(r);
        let t = &r.transport;
        stats["bounces"]["transport"] = json!({
            "bytes": t.bytes,
            "bytes_unbounded": t.bytes_unbounded,
            "kept_groups": t.kept_groups,
            "regathered_groups": t.regathered_groups,
            "read_slots": t.read_slots,
            "incident_bytes": t.incident_bytes,
            "slots": t.slots,
        });
    }
    stats["operators"] = json!(baked.operators.len());
    if a.keep_transport {
        stats["transport_file"] = json!({"path": transport_path, "bytes": transport_bytes});
    }
    let peak = wpbgi::compare::memory::peak();
    let per_surfel = bytes as f64 / baked.surfels.len().max(1) as f64;
    let total = start.elapsed().as_secs_f64();
    stats["peak_memory_bytes"] = json!(peak);
    stats["bytes"] = json!(bytes);
    stats["bytes_per_surfel"] = json!(per_surfel);
    stats["total_seconds"] = json!(total);
    if a.json {
        emit_json(json!({"event": "done", "output": a.output, "stats": stats}));
    } else {
        say!(
            "wrote {}: {} surfels, {} nodes, {} coefficients, {} bytes ({:.0} per surfel), {:.2} s{}",
            a.output.display(),
            baked.surfels.len(),
            baked.tree.nodes.len(),
            coefficients,
            bytes,
            per_surfel,
            total,
            peak.map_or(String::new(), |b| format!(", peak memory {} MB", b / 1_000_000)),
        );
        crate::say_stages(&baked.timings);
        if !baked.operators.is_empty() {
            say!(
                "  BSDF operators: {} (one per glossy BSDF without its tints, a textured \
                 roughness snapped to {} levels per octave of α)",
                baked.operators.len(),
                wpbgi::bake::bounce::bsdf_operator::ROUGHNESS_LEVELS_PER_OCTAVE
            );
        }
        if let Some(r) = &baked.bounces {
            crate::say_bounces(r);
            let t = &r.transport;
            let regathered = if t.regathered_groups > 0 {
                format!(
                    "; {} of {} receiver groups past the budget gathered again in every bounce",
                    t.regathered_groups,
                    t.kept_groups + t.regathered_groups
                )
            } else {
                String::new()
            };
            say!(
                "  transport: {} MB ({:.0} bytes per surfel) and {} MB of summed light, {} of {} \
                 surfels gather, {} of {} slots read{regathered}",
                t.bytes / 1_000_000,
                t.bytes as f64 / baked.surfels.len().max(1) as f64,
                t.incident_bytes / 1_000_000,
                t.receivers,
                baked.surfels.len(),
                t.read_slots,
                t.slots,
            );
        }
        if a.keep_transport {
            say!(
                "  transport kept in {} ({} MB){}",
                transport_path.display(),
                transport_bytes / 1_000_000,
                if transport_bytes == 0 {
                    ": none, the bake has no bounces"
                } else {
                    ""
                }
            );
        }
    }
    Ok(())
}

pub fn inspect_command(a: InspectArgs) -> Result<()> {
    let c = BakedCache::read(&a.cache, None)?;
    if let Some(p) = &a.scene {
        // The settings the cache was baked with are in it: hash the scene with those.
        let scene = crate::load_scene(p)?;
        c.check_scene(&scene)?;
    }
    let sections: Vec<Value> = c
        .cache
        .sections
        .iter()
        .map(|s| json!({"name": s.name, "offset": s.offset, "bytes": s.length, "checksum": format!("{:016x}", s.checksum)}))
        .collect();
    let hash = wpbgi::cache::hash_hex(c.cache.hash);
    // A transport kept beside the cache (`bake --keep-transport`); whether it fits an edit is
    // for `relight` to check.
    let transport_path = beside(&a.cache);
    let transport = std::fs::metadata(&transport_path)
        .ok()
        .filter(|m| m.is_file())
        .map(|m| json!({"path": transport_path, "bytes": m.len()}));
    let report = json!({
        "file": a.cache,
        "format_version": c.cache.version,
        "content_hash": hash,
        "bytes": c.cache.len(),
        "crate_version": c.plan["crate_version"],
        "settings": c.settings(),
        "plan": c.plan["plan"],
        "stats": c.plan["stats"],
        "sections": sections,
        "transport": transport,
    });
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!(
            "{} (wpbgi cache format {}, written by wpbgi {})",
            a.cache.display(),
            c.cache.version,
            c.plan["crate_version"]
        );
        println!("content hash {hash}, {} bytes", c.cache.len());
        println!("settings: {}", c.settings());
        println!("plan: {}", c.plan["plan"]);
        println!("stats: {}", c.plan["stats"]);
        println!("sections:");
        for s in &c.cache.sections {
            println!(
                "  {:<10} {:>12} bytes at {:>10}  xxh3 {:016x}",
                s.name, s.length, s.offset, s.checksum
            );
        }
        match &transport {
            Some(t) => println!(
                "transport kept beside it: {} ({} bytes; relight re-solves scattering edits from it)",
                transport_path.display(),
                t["bytes"]
            ),
            None => println!("no transport kept beside it (bake --keep-transport)"),
        }
    }
    if let Some(p) = &a.ply {
        write_ply(p, &c)?;
        say!("wrote {} ({} points)", p.display(), c.surfels.len());
    }
    Ok(())
}

/// An ASCII PLY point cloud: position, normal, and the surfel's radiance as 8-bit sRGB.
fn write_ply(path: &Path, c: &BakedCache) -> Result<()> {
    let mut out = String::new();
    out.push_str("ply\nformat ascii 1.0\ncomment wpbgi surfels: radiance as sRGB colour\n");
    out.push_str(&format!("element vertex {}\n", c.surfels.len()));
    for p in ["x", "y", "z", "nx", "ny", "nz"] {
        out.push_str(&format!("property float {p}\n"));
    }
    out.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n");
    let srgb = wpbgi::image::srgb8;
    for s in &c.surfels {
        out.push_str(&format!(
            "{} {} {} {} {} {} {} {} {}\n",
            s.p[0],
            s.p[1],
            s.p[2],
            s.n[0],
            s.n[1],
            s.n[2],
            srgb(s.rgb[0]),
            srgb(s.rgb[1]),
            srgb(s.rgb[2])
        ));
    }
    wpbgi::atomic::write_atomically(path, |tmp| {
        std::fs::write(tmp, &out).map_err(|e| e.to_string())
    })
    .with_context(|| format!("cannot write {}", path.display()))
}
