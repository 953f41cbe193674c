//! Mesh helpers shared by the import and the bake.

pub mod weld;

/// For every vertex, a representative of the connected piece it belongs to: vertices that
/// share one of `triangles` are in the same piece (union-find).
pub fn connected_pieces<'a>(
    vertices: usize,
    triangles: impl Iterator<Item = &'a [u32]>,
) -> Vec<u32> {
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    let mut parent: Vec<u32> = (0..vertices as u32).collect();
    for t in triangles {
        let a = find(&mut parent, t[0]);
        for &v in &t[1..] {
            let b = find(&mut parent, v);
            parent[b as usize] = a;
        }
    }
    (0..vertices as u32).map(|v| find(&mut parent, v)).collect()
}
