//! `lodlab study`: a perceptual study of level-of-detail methods run the way Merry, Marais &
//! Gain §6.2 ran theirs.
//!
//! - [`make`]: a plan (models, method pairs, pixel tolerances, participants) becomes one clip
//!   per distinct (model, method, tolerance), rendered once by `record`, and one session list per
//!   participant: every pair in both orders (to cancel ordering bias), shuffled per participant,
//!   after a training block of one sample per condition in a random order whose answers are
//!   discarded (the paper found a learning effect in its pilot).
//! - [`session`]: a participant's run: each pair's clips one after the other, never side by
//!   side, then a forced choice; every answer appended to `answers.csv` and flushed at once, so
//!   that a crash loses nothing and a session resumes where it stopped.
//! - [`web`]: the study as a static site that runs the sessions online, in a browser.
//! - [`analyze`]: per condition, the preference counts and share, and a two-sided binomial (sign)
//!   test, training answers excluded; a Markdown table and a bar chart.

pub mod analyze;
pub mod make;
pub mod plan;
pub mod proxy;
pub mod session;
pub mod shards;
pub mod web;
pub mod window;

pub use make::{MakeOptions, clip_options, make};
