//! `plugin/include/wpbgi.h` is what cbindgen generates from the Rust side (`cbindgen.toml`).
//! After changing the ABI, rewrite it with
//! `WPBGI_BLESS=1 cargo test --release -p wpbgi-plugin --test header`.

use std::path::Path;

#[test]
fn the_checked_in_header_matches_the_rust_side() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen reads plugin/src")
        .write(&mut generated);
    let header = dir.join("include/wpbgi.h");
    if std::env::var("WPBGI_BLESS").is_ok_and(|v| v == "1") {
        std::fs::write(&header, &generated).expect("write the header");
    }
    let checked_in = std::fs::read(&header).expect("plugin/include/wpbgi.h");
    assert!(
        checked_in == generated,
        "plugin/include/wpbgi.h is out of date with plugin/src: rewrite it with \
         WPBGI_BLESS=1 cargo test --release -p wpbgi-plugin --test header"
    );
}
