//! Spec parsing and validation on arbitrary text: an error or a spec, never a panic; a spec
//! that validates also yields its quick profile.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;
use visfield::experiment::spec::Spec;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match Spec::parse(text, Path::new("fuzz.json")) {
        Ok(spec) => {
            let _ = spec.profile(true);
            let _ = spec.profile(false);
        }
        Err(e) => assert!(e.to_string().starts_with("fuzz.json")),
    }
});
