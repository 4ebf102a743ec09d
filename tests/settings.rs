//! Every settings struct owns its defaults and refuses each field out of range with one
//! sentence that names the field (`Struct.field is VALUE; it must be RANGE`), and the entry
//! points refuse before any work rather than clamp.

use wpbgi::bake::bounce::BounceSettings;
use wpbgi::bake::{BakeSettings, Quality};
use wpbgi::compare::CompareSettings;
use wpbgi::reference::{RenderSettings, Transport};
use wpbgi::render::FinalSettings;
use wpbgi::Error;

/// `result` is a refusal naming `field` of `settings` and the `value` given.
fn refuses(result: Result<(), Error>, settings: &str, field: &str, value: &str) {
    match result {
        Err(Error::InvalidSetting(m)) => {
            let named = format!("{settings}.{field} is {value}; it must be ");
            assert!(m.starts_with(&named), "\"{m}\" does not start \"{named}\"");
            assert!(!m.contains('\n'), "one sentence: {m}");
        }
        other => panic!("{settings}.{field} = {value} was not refused: {other:?}"),
    }
}

#[test]
fn the_defaults_and_presets_are_valid() {
    for q in Quality::ALL {
        BakeSettings::preset(q).validate().expect("a preset");
        BakeSettings::preset(q)
            .direct_only()
            .validate()
            .expect("direct only");
    }
    BakeSettings::default().validate().expect("bake");
    BounceSettings::auto().validate().expect("auto bounces");
    FinalSettings::default().validate().expect("final");
    RenderSettings::default().validate().expect("reference");
    CompareSettings::default().validate().expect("compare");
    // The default bake is what `wpbgi bake` does: the preview preset with automatic bounces.
    assert_eq!(
        BakeSettings::default(),
        BakeSettings::preset(Quality::Preview)
    );
    assert_eq!(BakeSettings::default().bounces, BounceSettings::auto());
    assert_eq!(
        BakeSettings::preset(Quality::Draft).direct_only().bounces,
        BounceSettings::NONE
    );
}

#[test]
fn bake_settings_refuse_each_field_out_of_range() {
    let ok = BakeSettings::default();
    let with = |f: &dyn Fn(&mut BakeSettings)| {
        let mut s = ok.clone();
        f(&mut s);
        s.validate()
    };
    const S: &str = "BakeSettings";
    refuses(with(&|s| s.points = 0), S, "points", "0");
    refuses(
        with(&|s| s.points = u32::MAX as usize + 1),
        S,
        "points",
        "4294967296",
    );
    refuses(with(&|s| s.light_samples = 0), S, "light_samples", "0");
    refuses(with(&|s| s.tau = 1.0), S, "tau", "1");
    refuses(with(&|s| s.tau = -1e-3), S, "tau", "-0.001");
    refuses(with(&|s| s.tau = f32::NAN), S, "tau", "NaN");
    refuses(with(&|s| s.max_cut = 0), S, "max_cut", "0");
    refuses(
        with(&|s| s.surfel_density = vec![("glass".into(), 0.0)]),
        S,
        "surfel_density",
        "0 for material \"glass\"",
    );
    refuses(
        with(&|s| s.surfel_density = vec![("glass".into(), f32::INFINITY)]),
        S,
        "surfel_density",
        "inf for material \"glass\"",
    );
    // The bounces' fields, through the bake's settings.
    refuses(
        with(&|s| s.bounces.receiver_stride = 0),
        "BounceSettings",
        "receiver_stride",
        "0",
    );
}

#[test]
fn bounce_settings_refuse_each_field_out_of_range() {
    let with = |f: &dyn Fn(&mut BounceSettings)| {
        let mut s = BounceSettings::auto();
        f(&mut s);
        s.validate()
    };
    const S: &str = "BounceSettings";
    refuses(with(&|s| s.tolerance = 1.0), S, "tolerance", "1");
    refuses(with(&|s| s.tolerance = -0.5), S, "tolerance", "-0.5");
    refuses(with(&|s| s.operator_tau = 2.0), S, "operator_tau", "2");
    refuses(
        with(&|s| s.operator_tau = f32::NAN),
        S,
        "operator_tau",
        "NaN",
    );
    refuses(with(&|s| s.receiver_stride = 0), S, "receiver_stride", "0");
}

#[test]
fn final_settings_refuse_each_field_out_of_range() {
    let with = |f: &dyn Fn(&mut FinalSettings)| {
        let mut s = FinalSettings::default();
        f(&mut s);
        s.validate()
    };
    const S: &str = "FinalSettings";
    refuses(with(&|s| s.mb_size = 0), S, "mb_size", "0");
    refuses(with(&|s| s.mb_size = 15), S, "mb_size", "15");
    refuses(with(&|s| s.mb_size = 258), S, "mb_size", "258");
    refuses(with(&|s| s.glossy_below = -0.1), S, "glossy_below", "-0.1");
    refuses(with(&|s| s.glossy_below = 1.5), S, "glossy_below", "1.5");
    refuses(with(&|s| s.adaptive_share = 0.0), S, "adaptive_share", "0");
    refuses(with(&|s| s.adaptive_share = 2.0), S, "adaptive_share", "2");
    refuses(
        with(&|s| s.adaptive_levels = wpbgi::render::MAX_ADAPTIVE_LEVELS + 1),
        S,
        "adaptive_levels",
        &(wpbgi::render::MAX_ADAPTIVE_LEVELS + 1).to_string(),
    );
    refuses(with(&|s| s.light_samples = 0), S, "light_samples", "0");
    refuses(
        with(&|s| s.specular_below = f32::NAN),
        S,
        "specular_below",
        "NaN",
    );
    refuses(with(&|s| s.max_depth = 0), S, "max_depth", "0");
    refuses(with(&|s| s.max_depth = -2), S, "max_depth", "-2");
    refuses(with(&|s| s.clusters = 0), S, "clusters", "0");
    refuses(with(&|s| s.far_eps = -1.0), S, "far_eps", "-1");
    refuses(with(&|s| s.far_eps = f32::INFINITY), S, "far_eps", "inf");
    refuses(with(&|s| s.spp = 0), S, "spp", "0");
}

#[test]
fn reference_settings_refuse_each_field_out_of_range() {
    let with = |f: &dyn Fn(&mut RenderSettings)| {
        let mut s = RenderSettings::default();
        f(&mut s);
        s.validate()
    };
    const S: &str = "RenderSettings";
    refuses(with(&|s| s.spp = 0), S, "spp", "0");
    refuses(with(&|s| s.max_depth = 0), S, "max_depth", "0");
    refuses(with(&|s| s.max_depth = -7), S, "max_depth", "-7");
    refuses(
        with(&|s| {
            s.transport = Transport::CacheOneBounce {
                smooth_below: 3.0,
                chain: 8,
            }
        }),
        S,
        "transport.smooth_below",
        "3",
    );
}

#[test]
fn compare_settings_refuse_each_field_out_of_range() {
    let with = |f: &dyn Fn(&mut CompareSettings)| {
        let mut s = CompareSettings::default();
        f(&mut s);
        s.validate()
    };
    const S: &str = "CompareSettings";
    refuses(with(&|s| s.presets.clear()), S, "presets", "empty");
    refuses(with(&|s| s.reference_spp = 0), S, "reference_spp", "0");
    // The settings it holds are checked with it.
    refuses(
        with(&|s| s.final_settings.clusters = 0),
        "FinalSettings",
        "clusters",
        "0",
    );
    refuses(
        with(&|s| s.bounces.tolerance = 1.0),
        "BounceSettings",
        "tolerance",
        "1",
    );
}

/// The entry points refuse before any work: a bake of a bundled scene with a bad field
/// returns the field's refusal, not a clamped bake.
#[test]
fn the_bake_refuses_what_validate_refuses() {
    let scene = wpbgi::scene::Scene::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cbox-rough.gltf"),
    )
    .expect("the bundled scene");
    let settings = BakeSettings {
        max_cut: 0,
        ..BakeSettings::preset(Quality::Draft).direct_only()
    };
    let result = wpbgi::bake::bake(&scene, &settings, &|_, _| {}).map(|_| ());
    refuses(result, "BakeSettings", "max_cut", "0");
}
