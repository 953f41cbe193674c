//! The glTF importer on arbitrary bytes: every input must give a model or an error, within
//! the default limits, never a panic, a hang or an allocation the size of what a header claims.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodlab::import::gltf::from_bytes;
use lodlab::import::validate::Limits;

fuzz_target!(|data: &[u8]| {
    // External files resolve against a folder that does not exist: the fuzzer's inputs name
    // files, but nothing outside the input is read.
    let base = std::path::Path::new("/nonexistent-lodlab-fuzz");
    let _ = from_bytes("fuzz", data.to_vec(), base, &Limits::default());
});
