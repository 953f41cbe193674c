//! What the renderer holds, in bytes, by kind: the memory report of `shot`'s JSON line and
//! the viewer's statistics. On a software adapter (lavapipe) all of it is host memory and
//! counts in the process's resident size.

use serde::Serialize;

/// Bytes uploaded to the GPU, by what they hold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct GpuMemory {
    /// Bone matrices of every frame of every clip (one texture per character).
    pub animation_textures: u64,
    /// Animation-space vertices of every level of every method uploaded.
    pub vertex_textures: u64,
    pub index_buffers: u64,
    /// Material layers with their mipmaps: billboard-cloud atlases among them.
    pub material_textures: u64,
    /// Coarse levels' normal maps with their mipmaps.
    pub normal_maps: u64,
    /// Spectral clouds' DFT spectra.
    pub spectra_textures: u64,
    /// Every level's vertices in one pose for the plain calibration shader.
    pub calibration_vertices: u64,
    /// Instances, shadows, billboard outlines.
    pub other_buffers: u64,
}

impl GpuMemory {
    pub fn total(&self) -> u64 {
        self.rows().iter().map(|(_, b)| b).sum()
    }

    /// Names and bytes, largest kinds of data first as they usually are.
    pub fn rows(&self) -> [(&'static str, u64); 8] {
        [
            ("material textures", self.material_textures),
            ("vertex textures", self.vertex_textures),
            ("animation textures", self.animation_textures),
            ("index buffers", self.index_buffers),
            ("normal maps", self.normal_maps),
            ("calibration vertices", self.calibration_vertices),
            ("spectra textures", self.spectra_textures),
            ("other buffers", self.other_buffers),
        ]
    }
}

impl std::ops::AddAssign for GpuMemory {
    fn add_assign(&mut self, o: GpuMemory) {
        self.animation_textures += o.animation_textures;
        self.vertex_textures += o.vertex_textures;
        self.index_buffers += o.index_buffers;
        self.material_textures += o.material_textures;
        self.normal_maps += o.normal_maps;
        self.spectra_textures += o.spectra_textures;
        self.calibration_vertices += o.calibration_vertices;
        self.other_buffers += o.other_buffers;
    }
}

/// The process's resident set size now, where the platform says (Linux: /proc).
pub fn resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Hands memory freed on the heap back to the system, where the C library keeps it otherwise
/// (glibc): loading a forest's levels frees a few hundred MB of decoded chains and mipmap
/// scratch that would stay resident for the viewer's whole run.
pub fn return_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only walks glibc's own heap; it takes no pointers of ours.
    unsafe {
        libc::malloc_trim(0);
    }
}
