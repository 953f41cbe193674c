//! Impostors: a model's last level drawn as a picture of it. Trees get octahedral impostors
//! ([`octahedral`]), characters animated ones ([`animated`]): views by frames on a sheet.

pub mod animated;
pub mod nearest_view;
pub mod octahedral;
pub mod placement;
pub mod sheet;
