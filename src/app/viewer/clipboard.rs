//! The system clipboard "copy as command" writes to: arboard's on the desktop, the page's
//! (`navigator.clipboard`) in the browser.

/// A clipboard, kept once made (on X11 the text lives as long as it).
pub struct Clipboard {
    #[cfg(not(target_arch = "wasm32"))]
    system: arboard::Clipboard,
}

impl Clipboard {
    /// The clipboard, where there is one.
    pub fn new() -> Option<Clipboard> {
        #[cfg(not(target_arch = "wasm32"))]
        return arboard::Clipboard::new()
            .ok()
            .map(|system| Clipboard { system });
        #[cfg(target_arch = "wasm32")]
        web_sys::window().map(|_| Clipboard {})
    }

    /// Puts `text` on the clipboard; whether it went (the browser's answer comes later: a
    /// page the user has not interacted with is refused then, silently).
    pub fn set_text(&mut self, text: &str) -> bool {
        #[cfg(not(target_arch = "wasm32"))]
        return self.system.set_text(text.to_string()).is_ok();
        #[cfg(target_arch = "wasm32")]
        web_sys::window().is_some_and(|w| {
            let _ = w.navigator().clipboard().write_text(text);
            true
        })
    }
}
