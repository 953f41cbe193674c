//! Card trees: trees laid out as artists ship them for real-time engines, for testing the
//! billboard clouds on what users bring rather than on lodlab's own skeletal trees
//! ([`crate::generate::tree`]). Each is a prop (no skin, no clip: most trees from public
//! collections stand still), its foliage alpha-cut cards (`MASK`, double-sided), each with a
//! property the generated trees lack:
//!
//! - `card-palm`: a leaning trunk under 16 fronds, each a welded strip of 80 triangles folded
//!   along its rachis and drooping along its 2.4–3.2 m, so that no plane holds a frond within
//!   the finest levels' ε (a card bent at many places).
//! - `card-bush`: 500 leaf cards and 120 flower cards in two cut-out materials, each with its
//!   own texture and cutoff (0.5 for the leaves, 0.3 for the soft-edged blossoms), and no
//!   trunk; every triangle has vertices of its own (unwelded), as exporters split cards by
//!   face.
//! - `card-oak`: a trunk and six boughs under 180 leaf clusters, each three cards crossed on a
//!   shared spine (welded: one piece that no plane holds), with a tangent-space normal map and
//!   normals bent out from the crown's centre (the artists' trick for soft crowns), written in
//!   centimetres with Z up under a root node that turns it Y up and stretches it 1.3× in
//!   height.
//! - `card-pine`: 155 triangles, a five-sided trunk and 150 needle cards of one triangle each:
//!   a tree lighter than any billboard cloud of it.
//!
//! Each is written as a [`Document`], byte for byte the same on every run, and committed under
//! `assets/` like the other test models.

use super::file::{DocMesh, DocNode, DocPrimitive, Document};
use crate::generate::finish::{fbm, smooth};
use crate::generate::tree::{bark_texture, foliage_texture, srgb};
use crate::model::{Material, Rgba8Image, SkinnedMesh, Trs};
use glam::{Quat, Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// One primitive's vertices and triangles as they are built, before they are written.
#[derive(Default)]
struct Prim {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    indices: Vec<u32>,
}

impl Prim {
    fn vertex(&mut self, p: Vec3, n: Vec3, uv: Vec2) -> u32 {
        self.positions.push(p);
        self.normals.push(n.normalize_or(Vec3::Y));
        self.uvs.push(uv);
        self.positions.len() as u32 - 1
    }

    /// A quad `a b c d` (counter-clockwise) as two triangles sharing its vertices.
    fn quad(&mut self, v: [u32; 4]) {
        self.indices
            .extend_from_slice(&[v[0], v[1], v[2], v[0], v[2], v[3]]);
    }

    /// A card of corners `p` (counter-clockwise, from the bottom left) and normal `n`, its
    /// texture upright on it (v = 1 at the bottom edge); `welded`: the two triangles share
    /// the diagonal's vertices, else each triangle has vertices of its own.
    fn card(&mut self, p: [Vec3; 4], n: Vec3, welded: bool) {
        let uv = [
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
        ];
        if welded {
            let v = [0, 1, 2, 3].map(|k| self.vertex(p[k], n, uv[k]));
            self.quad(v);
        } else {
            for tri in [[0, 1, 2], [0, 2, 3]] {
                for k in tri {
                    let v = self.vertex(p[k], n, uv[k]);
                    self.indices.push(v);
                }
            }
        }
    }

    /// A tube along `axis` (points, bottom to top) of radius `radius(s)` (s from 0 to 1),
    /// `sides` round, capped at the top, textured by `v_scale` metres a texture height.
    fn tube(&mut self, axis: &[Vec3], sides: usize, radius: impl Fn(f32) -> f32, v_scale: f32) {
        let rings = axis.len();
        let mut rows: Vec<Vec<u32>> = Vec::with_capacity(rings);
        let mut along = 0.0;
        for (i, &c) in axis.iter().enumerate() {
            let d = if i + 1 < rings {
                axis[i + 1] - c
            } else {
                c - axis[i - 1]
            }
            .normalize_or(Vec3::Y);
            if i > 0 {
                along += c.distance(axis[i - 1]);
            }
            let side = perpendicular(d);
            let up = d.cross(side);
            let r = radius(i as f32 / (rings - 1).max(1) as f32);
            let row = (0..=sides)
                .map(|k| {
                    let a = TAU * k as f32 / sides as f32;
                    let n = side * a.cos() + up * a.sin();
                    self.vertex(
                        c + n * r,
                        n,
                        Vec2::new(k as f32 / sides as f32, along / v_scale),
                    )
                })
                .collect();
            rows.push(row);
        }
        for i in 0..rings - 1 {
            for k in 0..sides {
                let (a, b) = (rows[i][k], rows[i][k + 1]);
                let (c, d) = (rows[i + 1][k + 1], rows[i + 1][k]);
                self.quad([a, b, c, d]);
            }
        }
        let top = axis[rings - 1];
        let d = (top - axis[rings - 2]).normalize_or(Vec3::Y);
        let centre = self.vertex(top, d, Vec2::new(0.5, along / v_scale));
        for k in 0..sides {
            let (a, b) = (rows[rings - 1][k], rows[rings - 1][k + 1]);
            self.indices.extend_from_slice(&[a, b, centre]);
        }
    }

    fn into_primitive(self, material: usize) -> DocPrimitive {
        let n = self.positions.len();
        let mut mesh = SkinnedMesh::empty();
        mesh.positions = self.positions;
        mesh.normals = self.normals;
        mesh.uvs = self.uvs;
        mesh.materials = vec![material as u16; n];
        mesh.indices = self.indices;
        DocPrimitive {
            mesh,
            material: Some(material),
            targets: Vec::new(),
        }
    }
}

/// A unit vector at right angles to `d`.
fn perpendicular(d: Vec3) -> Vec3 {
    let a = if d.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
    a.cross(d).normalize()
}

/// A document of one mesh node (under `root`, where given) holding `prims`.
fn prop(name: &str, materials: Vec<Material>, prims: Vec<DocPrimitive>, root: Trs) -> Document {
    let mut doc = Document {
        generator: format!("lodlab gen-assets ({name})"),
        materials,
        ..Default::default()
    };
    doc.meshes.push(DocMesh {
        name: name.to_string(),
        primitives: prims,
    });
    doc.nodes.push(DocNode {
        name: name.to_string(),
        parent: None,
        rest: root,
        mesh: Some(0),
        skin: None,
    });
    doc
}

/// A texture `width` × `height` painted by `f(u, v)` (each in 0..1, v down the image) into
/// linear colour and alpha.
fn paint(width: u32, height: u32, f: impl Fn(Vec2) -> (Vec3, f32)) -> Rgba8Image {
    let mut pixels = Vec::with_capacity((width * height * 4) as usize);
    for y in 0..height {
        for x in 0..width {
            let p = Vec2::new(
                (x as f32 + 0.5) / width as f32,
                (y as f32 + 0.5) / height as f32,
            );
            let (c, a) = f(p);
            pixels.extend(srgb(c, a));
        }
    }
    Rgba8Image {
        width,
        height,
        pixels,
    }
}

/// A palm frond seen from above: a rachis up the middle (u = 1/2) from its base (v = 1) to
/// its tip (v = 0), and pairs of slender leaflets slanting towards the tip, with the
/// gaps between them cut out.
fn frond_texture() -> Rgba8Image {
    paint(128, 512, |p| {
        let along = 1.0 - p.y;
        let across = (p.x - 0.5).abs() * 2.0;
        let shade = fbm(Vec3::new(p.x * 6.0, p.y * 24.0, 5.0));
        if across < 0.05 && along < 0.98 {
            return (Vec3::new(0.28, 0.3, 0.12), 1.0);
        }
        // Leaflets: 28 a side, each leaving the rachis and slanting tipwards as it goes out.
        let phase = (along * 28.0 - across * 2.2).fract();
        let leaflet = phase < 0.55 && across < 0.98 && along > 0.03;
        if leaflet {
            let mid = 1.0 - (phase / 0.55 * 2.0 - 1.0).abs();
            let c = Vec3::new(0.12, 0.3, 0.06) * (0.75 + 0.4 * shade) * (0.8 + 0.3 * mid);
            (c, 1.0)
        } else {
            (Vec3::new(0.12, 0.28, 0.06), 0.0)
        }
    })
}

/// Five blossoms of five petals, pink round a yellow heart, their edges soft: alpha falls
/// from one to nothing over the outer third of each petal, so the material's cutoff (0.3)
/// decides how large they look.
fn blossom_texture() -> Rgba8Image {
    let centres = [
        (Vec2::new(0.3, 0.3), 0.2),
        (Vec2::new(0.72, 0.28), 0.17),
        (Vec2::new(0.5, 0.62), 0.22),
        (Vec2::new(0.2, 0.75), 0.15),
        (Vec2::new(0.8, 0.74), 0.16),
    ];
    paint(128, 128, |p| {
        let mut best = (Vec3::new(0.8, 0.35, 0.5), 0.0f32);
        for (k, &(c, r)) in centres.iter().enumerate() {
            let q = p - c;
            let d = q.length() / r;
            let angle = q.y.atan2(q.x) + k as f32;
            // Five petals: the radius swells and narrows round the heart.
            let petal = 0.62 + 0.38 * (2.5 * angle).cos().abs();
            let edge = d / petal;
            let alpha = 1.0 - smooth(0.55, 1.0, edge);
            if alpha > best.1 {
                let heart = 1.0 - smooth(0.12, 0.2, d);
                let pink = Vec3::new(0.85, 0.32, 0.52) * (0.85 + 0.3 * (1.0 - edge));
                let colour = pink * (1.0 - heart) + Vec3::new(0.9, 0.75, 0.1) * heart;
                best = (colour, alpha);
            }
        }
        best
    })
}

/// A tangent-space normal map of the broadleaf's leaf cluster: each texel's normal tilted by
/// the slope of a height made of veins and a little relief (x right, y up the texture).
fn leaf_normal_map() -> Rgba8Image {
    let size = 128u32;
    let height = |p: Vec2| {
        let veins = 1.0 - smooth(0.0, 0.03, ((p.x - 0.5) * 1.8 + (p.y - 0.9) * 0.6).abs());
        fbm(Vec3::new(p.x * 10.0, p.y * 10.0, 2.0)) * 0.6 - 0.4 * veins
    };
    let mut pixels = Vec::with_capacity((size * size * 4) as usize);
    let step = 1.0 / size as f32;
    for y in 0..size {
        for x in 0..size {
            let p = Vec2::new((x as f32 + 0.5) * step, (y as f32 + 0.5) * step);
            let dx = (height(p + Vec2::X * step) - height(p - Vec2::X * step)) / (2.0 * step);
            let dy = (height(p + Vec2::Y * step) - height(p - Vec2::Y * step)) / (2.0 * step);
            // v grows down the image: up the texture is −y.
            let n = Vec3::new(-dx * 0.05, dy * 0.05, 1.0).normalize();
            let byte = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
            pixels.extend([byte(n.x), byte(n.y), byte(n.z), 255]);
        }
    }
    Rgba8Image {
        width: size,
        height: size,
        pixels,
    }
}

/// "card-palm": see the module comment. About 8 m tall, 1,480 triangles.
pub fn card_palm() -> Document {
    let mut rng = fastrand::Rng::with_seed(17);
    let trunk_height = 6.0;
    let axis: Vec<Vec3> = (0..=12)
        .map(|i| {
            let y = trunk_height * i as f32 / 12.0;
            let s = y / trunk_height;
            Vec3::new(0.6 * s * s, y, 0.15 * s * s)
        })
        .collect();
    let top = axis[12];
    let mut bark = Prim::default();
    bark.tube(&axis, 8, |s| 0.2 - 0.08 * s, 1.5);

    let mut fronds = Prim::default();
    for k in 0..16 {
        let azimuth = k as f32 * 2.399_963 + rng.f32() * 0.3;
        let t = k as f32 / 15.0;
        let elevation = (55.0 - 90.0 * t + rng.f32() * 10.0).to_radians();
        let length = 2.4 + 0.8 * rng.f32();
        let out = Vec3::new(azimuth.cos(), 0.0, azimuth.sin());
        let dir = out * elevation.cos() + Vec3::Y * elevation.sin();
        let side = Vec3::Y.cross(out).normalize();
        // The rachis arcs down under its own weight: its tip 0.45 of the frond's length below
        // where a straight frond would end.
        let rachis = |s: f32| top + dir * (s * length) - Vec3::Y * (0.45 * length * s * s);
        let tangent = |s: f32| (dir - Vec3::Y * (0.9 * s)).normalize();
        let fold = 25f32.to_radians();
        let mut rows: Vec<[u32; 3]> = Vec::new();
        for i in 0..=20 {
            let s = i as f32 / 20.0;
            let p = rachis(s);
            let t = tangent(s);
            let mut up = side.cross(t).normalize();
            if up.y < 0.0 {
                up = -up;
            }
            let w = (0.45 * (PI * s.powf(0.8)).sin()).max(0.03);
            let (across, lift) = (side * w * fold.cos(), up * w * fold.sin());
            let v = 1.0 - s;
            rows.push([
                fronds.vertex(p - across + lift, up, Vec2::new(0.0, v)),
                fronds.vertex(p, up, Vec2::new(0.5, v)),
                fronds.vertex(p + across + lift, up, Vec2::new(1.0, v)),
            ]);
        }
        for i in 0..20 {
            let (a, b) = (rows[i], rows[i + 1]);
            fronds.quad([a[0], a[1], b[1], b[0]]);
            fronds.quad([a[1], a[2], b[2], b[1]]);
        }
    }
    prop(
        "card-palm",
        vec![
            Material::opaque("palm bark", [0.8, 0.75, 0.7, 1.0], Some(bark_texture())),
            Material::cut_out("frond", [1.0; 4], Some(frond_texture())),
        ],
        vec![bark.into_primitive(0), fronds.into_primitive(1)],
        Trs::IDENTITY,
    )
}

/// A point inside the unit ball, `r` of the way out, in a random direction.
fn in_ball(rng: &mut fastrand::Rng, r: f32) -> Vec3 {
    loop {
        let d = Vec3::new(
            rng.f32() * 2.0 - 1.0,
            rng.f32() * 2.0 - 1.0,
            rng.f32() * 2.0 - 1.0,
        );
        if d.length_squared() > 1e-4 && d.length_squared() <= 1.0 {
            return d.normalize() * r;
        }
    }
}

/// A card of side `size` at `centre` facing `normal`, turned by `spin` about it.
fn card_corners(centre: Vec3, normal: Vec3, size: f32, spin: f32) -> [Vec3; 4] {
    let a = perpendicular(normal);
    let b = normal.cross(a);
    let (u, v) = (
        (a * spin.cos() + b * spin.sin()) * size * 0.5,
        (b * spin.cos() - a * spin.sin()) * size * 0.5,
    );
    [
        centre - u - v,
        centre + u - v,
        centre + u + v,
        centre - u + v,
    ]
}

/// "card-bush": see the module comment. About 1.2 m tall, 1,240 triangles.
pub fn card_bush() -> Document {
    let mut rng = fastrand::Rng::with_seed(23);
    let centre = Vec3::new(0.0, 0.6, 0.0);
    let radii = Vec3::new(0.85, 0.6, 0.85);
    let place = |rng: &mut fastrand::Rng, r: f32, tilt: f32| {
        let d = in_ball(rng, r);
        let mut p = centre + d * radii;
        p.y = p.y.max(0.08);
        let outward = (d / radii).normalize_or(Vec3::Y);
        let normal = (outward + in_ball(rng, tilt)).normalize_or(Vec3::Y);
        (p, normal, rng.f32() * TAU)
    };
    let mut leaves = Prim::default();
    for _ in 0..500 {
        let r = 0.35 + 0.65 * rng.f32().sqrt();
        let (p, n, spin) = place(&mut rng, r, 0.8);
        leaves.card(card_corners(p, n, 0.26, spin), n, false);
    }
    let mut flowers = Prim::default();
    for _ in 0..120 {
        let r = 0.88 + 0.12 * rng.f32();
        let (p, n, spin) = place(&mut rng, r, 0.4);
        flowers.card(card_corners(p, n, 0.2, spin), n, false);
    }
    let blossom = Material {
        alpha_cutoff: 0.3,
        ..Material::cut_out("blossom", [1.0, 0.92, 0.96, 1.0], Some(blossom_texture()))
    };
    prop(
        "card-bush",
        vec![
            Material::cut_out("bush leaf", [1.0; 4], Some(foliage_texture(false))),
            blossom,
        ],
        vec![leaves.into_primitive(0), flowers.into_primitive(1)],
        Trs::IDENTITY,
    )
}

/// The card-oak's root node: Z up to Y up, centimetres to metres, 1.3× taller.
fn oak_root() -> Trs {
    Trs {
        translation: Vec3::ZERO,
        rotation: Quat::from_rotation_x(-PI / 2.0),
        scale: Vec3::new(0.01, 0.01, 0.013),
    }
}

/// "card-oak": see the module comment. About 8 m tall, 2,700 triangles.
pub fn card_oak() -> Document {
    let mut rng = fastrand::Rng::with_seed(31);
    let mut bark = Prim::default();
    let trunk: Vec<Vec3> = (0..=6)
        .map(|i| Vec3::new(0.0, 5.5 * i as f32 / 6.0, 0.0))
        .collect();
    bark.tube(&trunk, 10, |s| 0.32 - 0.2 * s, 2.0);
    let crown = Vec3::new(0.0, 5.4, 0.0);
    for k in 0..6 {
        let azimuth = k as f32 * TAU / 6.0 + 0.3 * rng.f32();
        let out = Vec3::new(azimuth.cos(), 0.0, azimuth.sin());
        let base = Vec3::new(0.0, 2.7 + 0.1 * k as f32, 0.0);
        let dir = (out * 0.75 + Vec3::Y * 0.66).normalize();
        let axis: Vec<Vec3> = (0..=4)
            .map(|i| {
                let s = i as f32 / 4.0;
                base + dir * (2.8 * s) + Vec3::Y * (0.4 * s * s)
            })
            .collect();
        bark.tube(&axis, 8, |s| 0.12 - 0.08 * s, 2.0);
    }
    // Leaf clusters on the crown's shell: three cards crossed on a shared spine that points
    // outwards, their normals bent out from the crown's centre.
    let mut leaves = Prim::default();
    let radii = Vec3::new(2.9, 2.1, 2.9);
    for _ in 0..180 {
        let r = 0.55 + 0.45 * rng.f32().sqrt();
        let d = in_ball(&mut rng, r);
        let p = crown + d * radii;
        let spine = ((d / radii).normalize_or(Vec3::Y) + in_ball(&mut rng, 0.5)).normalize();
        let (length, width) = (0.9, 0.7);
        let bent = |q: Vec3| (q - crown).normalize_or(Vec3::Y);
        let base = p - spine * (length * 0.5);
        let tip = p + spine * (length * 0.5);
        let b = leaves.vertex(base, bent(base), Vec2::new(0.5, 1.0));
        let t = leaves.vertex(tip, bent(tip), Vec2::new(0.5, 0.0));
        let across = perpendicular(spine);
        let spin = rng.f32() * PI;
        for k in 0..3 {
            let a = spin + k as f32 * PI / 3.0;
            let w = (across * a.cos() + spine.cross(across) * a.sin()) * (width * 0.5);
            let corner = |q: Vec3, uv: Vec2, leaves: &mut Prim| leaves.vertex(q, bent(q), uv);
            let lb = corner(base - w, Vec2::new(0.0, 1.0), &mut leaves);
            let lt = corner(tip - w, Vec2::new(0.0, 0.0), &mut leaves);
            let rb = corner(base + w, Vec2::new(1.0, 1.0), &mut leaves);
            let rt = corner(tip + w, Vec2::new(1.0, 0.0), &mut leaves);
            leaves.quad([lb, b, t, lt]);
            leaves.quad([b, rb, rt, t]);
        }
    }
    // Written in the file's space: centimetres, Z up, squashed so that the root's stretch
    // makes it the tree above; normals by the transpose of the root's matrix (the inverse of
    // how a reader turns them back).
    let root = oak_root();
    let to_file = root.matrix().inverse();
    let normal_to_file = glam::Mat3::from(root.matrix().matrix3).transpose();
    for prim in [&mut bark, &mut leaves] {
        for p in &mut prim.positions {
            *p = to_file.transform_point3(*p);
        }
        for n in &mut prim.normals {
            *n = (normal_to_file * *n).normalize_or(Vec3::Z);
        }
    }
    let mut doc = prop(
        "card-oak",
        vec![
            Material::opaque("oak bark", [1.0; 4], Some(bark_texture())),
            Material::cut_out(
                "oak leaves",
                [0.9, 1.0, 0.85, 1.0],
                Some(foliage_texture(false)),
            ),
        ],
        vec![bark.into_primitive(0), leaves.into_primitive(1)],
        root,
    );
    doc.normal_maps.push((1, leaf_normal_map()));
    doc
}

/// "card-pine": see the module comment. About 5 m tall, 155 triangles.
pub fn card_pine() -> Document {
    let mut rng = fastrand::Rng::with_seed(41);
    let mut bark = Prim::default();
    let apex = Vec3::new(0.0, 5.0, 0.0);
    let ring: Vec<u32> = (0..=5)
        .map(|k| {
            let a = TAU * k as f32 / 5.0;
            let n = Vec3::new(a.cos(), 0.03, a.sin());
            bark.vertex(
                n * 0.16 * Vec3::new(1.0, 0.0, 1.0),
                n,
                Vec2::new(k as f32 / 5.0, 3.0),
            )
        })
        .collect();
    for k in 0..5 {
        let a = TAU * (k as f32 + 0.5) / 5.0;
        let top = bark.vertex(apex, Vec3::new(a.cos(), 0.03, a.sin()), Vec2::new(0.5, 0.0));
        bark.indices.extend_from_slice(&[ring[k + 1], ring[k], top]);
    }
    // Ten whorls of fifteen needle cards, each a triangle from a short base at the trunk out
    // to a drooping tip, shorter towards the top.
    let mut needles = Prim::default();
    for whorl in 0..10 {
        let h = 1.0 + 3.8 * whorl as f32 / 9.0;
        let reach = 0.35 + 1.5 * (1.0 - (h - 1.0) / 4.2);
        for k in 0..15 {
            let a = TAU * (k as f32 + 0.5 * (whorl % 2) as f32) / 15.0 + 0.15 * rng.f32();
            let out = Vec3::new(a.cos(), 0.0, a.sin());
            let side = Vec3::Y.cross(out).normalize() * (0.18 + 0.06 * rng.f32());
            let root = Vec3::new(0.0, h, 0.0) + out * 0.05;
            let tip = root + out * reach - Vec3::Y * (0.35 * reach + 0.1 * rng.f32());
            let n = (tip - root).cross(side).normalize();
            let n = if n.y < 0.0 { -n } else { n };
            let p = [root - side, root + side, tip];
            let uv = [
                Vec2::new(0.0, 1.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.5, 0.0),
            ];
            for k in 0..3 {
                let v = needles.vertex(p[k], n, uv[k]);
                needles.indices.push(v);
            }
        }
    }
    prop(
        "card-pine",
        vec![
            Material::opaque("pine bark", [0.7, 0.6, 0.5, 1.0], Some(bark_texture())),
            Material::cut_out("pine needles", [1.0; 4], Some(foliage_texture(true))),
        ],
        vec![bark.into_primitive(0), needles.into_primitive(1)],
        Trs::IDENTITY,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangles(doc: &Document) -> Vec<usize> {
        doc.meshes[0]
            .primitives
            .iter()
            .map(|p| p.mesh.indices.len() / 3)
            .collect()
    }

    #[test]
    fn the_card_trees_have_the_sizes_they_stand_for() {
        assert_eq!(triangles(&card_palm()), [8 * 12 * 2 + 8, 16 * 80]);
        assert_eq!(triangles(&card_bush()), [1000, 240]);
        assert_eq!(
            triangles(&card_oak()),
            [10 * 6 * 2 + 10 + 6 * (8 * 4 * 2 + 8), 180 * 12]
        );
        assert_eq!(triangles(&card_pine()).iter().sum::<usize>(), 155);
    }

    #[test]
    fn the_bush_is_unwelded_and_the_oak_is_normal_mapped_under_a_stretched_root() {
        let bush = card_bush();
        for p in &bush.meshes[0].primitives {
            let mut seen = std::collections::HashSet::new();
            assert!(p.mesh.indices.iter().all(|&v| seen.insert(v)), "unwelded");
        }
        assert_eq!(bush.materials[1].alpha_cutoff, 0.3);
        let oak = card_oak();
        assert_eq!(oak.normal_maps.len(), 1);
        let s = oak.nodes[0].rest.scale;
        assert!(s.z > s.x * 1.2, "stretched: {s}");
    }
}
