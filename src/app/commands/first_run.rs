//! What the first run on a machine says before it bakes: the commands that show a scene call
//! [`first_run_note`].

/// Says once, where the cache is empty (the first run on a machine), what is about to happen:
/// the levels of detail bake before (or while) anything is shown, where they are kept and how
/// to clear them. Later runs read them from the cache and say nothing.
pub fn first_run_note(cache: Option<&std::path::Path>, waits: bool) {
    let dir = crate::bake::cache::LodCache::new(cache.map(|d| d.to_path_buf())).dir;
    let empty = std::fs::read_dir(&dir).map_or(true, |mut d| d.next().is_none());
    if !empty {
        return;
    }
    let how = if waits {
        "this waits for them, a minute or two on 2 cores for the default scene"
    } else {
        "they bake in the background, a minute or two on 2 cores for the default scene, and full detail is drawn until each model's are in"
    };
    eprintln!(
        "lodlab: first run: the models' levels of detail are baked now ({how}) and kept in {} for next time (rm -r it to clear; --cache DIR for another folder)",
        dir.display()
    );
}
