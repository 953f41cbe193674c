//! Foliage: Bennett-Therkildsen, Carlsen & Schmid's animated billboard clouds. A tree's leaves
//! become billboards ([`billboard`]) that move by the DFT spectra of the leaves they stand in
//! for ([`spectral`]).

pub mod billboard;
pub mod classify;
pub mod patch;
pub mod spectral;
