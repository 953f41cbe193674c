//! The bake cache's decoder on arbitrary bytes. Half the inputs are taken as whole cache files
//! (the header checks); the other half are wrapped in a valid header with a matching checksum,
//! so that the LZ4 and postcard decoding behind the checksum are reached too.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lodlab::bake::cache::{Lookup, decode, encode};
use lodlab::bake::character::lod::SkinnedLods;

fuzz_target!(|data: &[u8]| {
    let key = [0x5a; 32];
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let bytes = if mode & 1 == 0 {
        rest.to_vec()
    } else {
        encode(&key, rest)
    };
    let _: Lookup<SkinnedLods> = decode(&bytes, &key);
});
