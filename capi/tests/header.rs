//! The checked-in header `include/strata.h` is what cbindgen generates from this crate
//! now: header and library never disagree. With `STRATA_BLESS_HEADER=1` the test writes
//! the fresh header instead (after a change to the API).

use std::path::Path;

#[test]
fn the_checked_in_header_is_a_fresh_generation() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml"))
        .expect("capi/cbindgen.toml reads");
    let mut fresh = Vec::new();
    cbindgen::Builder::new()
        .with_crate(crate_dir)
        .with_config(config)
        .generate()
        .expect("cbindgen generates the header")
        .write(&mut fresh);
    let fresh = String::from_utf8(fresh).expect("the header is UTF-8");
    let path = crate_dir.join("include/strata.h");
    if std::env::var_os("STRATA_BLESS_HEADER").is_some() {
        std::fs::write(&path, &fresh).expect("writes include/strata.h");
        return;
    }
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        checked_in == fresh,
        "capi/include/strata.h is not what cbindgen generates from capi/src now; \
         regenerate it: STRATA_BLESS_HEADER=1 cargo test --release -p strata-capi --test header"
    );
}
