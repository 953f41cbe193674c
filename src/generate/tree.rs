//! The demo trees: cyclically animated skeletal tree models (CASTM, Bennett-Therkildsen, Carlsen &
//! Schmid, "Animated Billboard Clouds for Foliage Simplification", Aalborg University, 2007 §1.4).
//!
//! - **Skeleton:** one bone per branch segment, the trunk a chain of bones from the ground and
//!   every branch a chain hanging from the segment of its parent it grows from, four
//!   generations of branches deep. Joints sit inside the wood; there is no bone per leaf.
//! - **Wood:** one skinned mesh of capped tubes (each closed), one per branch, tapering from
//!   base to tip. Rings near a joint blend the two bones meeting there ([`Chain::weights`]), and
//!   the base ring of a branch blends with the segment it grows from, so nothing cracks.
//! - **Foliage:** loose alpha-textured quads, every one bound to exactly one bone with weight 1
//!   (the thesis's foliage rule §1.3): the segment of the branch it hangs from.
//! - **Wind:** one looping clip. Every bone bends about two axes across it with a few sinusoids
//!   of whole cycles per loop (so the loop is seamless); frequency rises with branch depth and
//!   amplitude falls with branch thickness, as the thesis observes of real trees (§1.5), and the
//!   trunk leans a little with the wind.
//!
//! Textures (bark, and a leaf cluster or a needle spray with a leaf-shaped alpha) are drawn here.

use super::cage::Weights;
use super::finish::{fbm, smooth};
use super::rig::{Chain, Pose, Rig, bake_clip, wave};
use crate::model::{Influence, Material, Model, Rgba8Image, SkinnedMesh};
use glam::{Quat, Vec2, Vec3};

/// Seconds in the wind loop.
pub const WIND_SECONDS: f32 = 6.0;
/// Side of the leaf and bark textures.
const TEXTURE_SIZE: u32 = 256;
const BARK: u16 = 0;
const FOLIAGE: u16 = 1;

/// How one generation of branches grows from its parent.
#[derive(Clone, Copy, Debug)]
struct Generation {
    /// Children per parent branch.
    children: usize,
    /// Bones per branch.
    segments: usize,
    /// Length relative to the parent's.
    length: f32,
    /// Angle from the parent's direction, degrees.
    angle: f32,
    /// Where along the parent children start, as a fraction of its length.
    start: f32,
}

/// What makes a species.
#[derive(Clone, Debug)]
struct Species {
    name: &'static str,
    height: f32,
    trunk_radius: f32,
    trunk_segments: usize,
    generations: [Generation; 4],
    /// Conifers grow their first generation in whorls of near-horizontal branches that shorten
    /// towards the top; broad-leaved trees spread theirs from the upper trunk.
    conifer: bool,
    /// Leaf quads per bone of the generations that carry foliage, and their side in metres.
    leaves_per_bone: usize,
    leaf_size: f32,
    /// Lowest generation that carries foliage (0 is the trunk).
    foliage_from: usize,
    seed: u64,
}

fn broadleaf_species() -> Species {
    Species {
        name: "broadleaf",
        height: 7.0,
        trunk_radius: 0.22,
        trunk_segments: 4,
        generations: [
            Generation {
                children: 6,
                segments: 3,
                length: 0.66,
                angle: 52.0,
                start: 0.38,
            },
            Generation {
                children: 3,
                segments: 2,
                length: 0.55,
                angle: 40.0,
                start: 0.3,
            },
            Generation {
                children: 2,
                segments: 1,
                length: 0.6,
                angle: 42.0,
                start: 0.35,
            },
            Generation {
                children: 2,
                segments: 1,
                length: 0.65,
                angle: 38.0,
                start: 0.4,
            },
        ],
        conifer: false,
        leaves_per_bone: 42,
        leaf_size: 0.42,
        foliage_from: 3,
        seed: 11,
    }
}

/// A small broad-leaved tree with about as many leaf quads (672) as the tree of the thesis's
/// results (§8.4.1: 692 quads), for a direct comparison of billboard counts and colour error.
fn sapling_species() -> Species {
    Species {
        name: "sapling",
        height: 4.0,
        trunk_radius: 0.12,
        trunk_segments: 3,
        generations: [
            Generation {
                children: 4,
                segments: 2,
                length: 0.72,
                angle: 55.0,
                start: 0.32,
            },
            Generation {
                children: 3,
                segments: 1,
                length: 0.6,
                angle: 40.0,
                start: 0.3,
            },
            Generation {
                children: 2,
                segments: 1,
                length: 0.62,
                angle: 42.0,
                start: 0.35,
            },
            Generation {
                children: 2,
                segments: 1,
                length: 0.65,
                angle: 38.0,
                start: 0.4,
            },
        ],
        conifer: false,
        leaves_per_bone: 14,
        leaf_size: 0.5,
        foliage_from: 4,
        seed: 5,
    }
}

fn conifer_species() -> Species {
    Species {
        name: "conifer",
        height: 10.0,
        trunk_radius: 0.2,
        trunk_segments: 6,
        generations: [
            Generation {
                children: 20,
                segments: 2,
                length: 0.3,
                angle: 95.0,
                start: 0.18,
            },
            Generation {
                children: 2,
                segments: 1,
                length: 0.5,
                angle: 55.0,
                start: 0.3,
            },
            Generation {
                children: 1,
                segments: 1,
                length: 0.6,
                angle: 35.0,
                start: 0.5,
            },
            Generation {
                children: 1,
                segments: 1,
                length: 0.6,
                angle: 30.0,
                start: 0.5,
            },
        ],
        conifer: true,
        leaves_per_bone: 40,
        leaf_size: 0.55,
        foliage_from: 1,
        seed: 23,
    }
}

/// One branch: its bones and the points between them (heads, then the tip).
#[derive(Clone, Debug)]
struct Branch {
    chain: Chain,
    generation: usize,
    base_radius: f32,
    tip_radius: f32,
}

impl Branch {
    fn direction(&self) -> Vec3 {
        (*self.chain.points.last().unwrap() - self.chain.points[0]).normalize_or(Vec3::Y)
    }

    fn length(&self) -> f32 {
        self.chain
            .points
            .windows(2)
            .map(|w| w[0].distance(w[1]))
            .sum()
    }

    fn radius(&self, s: f32) -> f32 {
        let t = s / self.chain.bones.len() as f32;
        self.base_radius + (self.tip_radius - self.base_radius) * t
    }
}

/// Any unit vector perpendicular to `d`.
fn perpendicular(d: Vec3) -> Vec3 {
    let a = if d.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
    d.cross(a).normalize()
}

/// Grows the skeleton: trunk, then every generation.
fn grow(sp: &Species, rig: &mut Rig, rng: &mut fastrand::Rng) -> Vec<Branch> {
    let mut branches = Vec::new();
    // The trunk, slightly bent.
    let lean = Vec3::new(rng.f32() - 0.5, 0.0, rng.f32() - 0.5) * 0.08;
    let trunk_points: Vec<Vec3> = (0..=sp.trunk_segments)
        .map(|k| {
            let t = k as f32 / sp.trunk_segments as f32;
            Vec3::new(0.0, sp.height * t, 0.0) + lean * sp.height * t * t
        })
        .collect();
    let mut bones = Vec::new();
    for (k, &head) in trunk_points[..sp.trunk_segments].iter().enumerate() {
        let parent = bones.last().copied();
        bones.push(rig.bone(&format!("trunk{k}"), parent, head));
    }
    branches.push(Branch {
        chain: Chain::new(rig, &bones, trunk_points[sp.trunk_segments]),
        generation: 0,
        base_radius: sp.trunk_radius,
        tip_radius: sp.trunk_radius * 0.18,
    });
    let golden = 137.5f32.to_radians();
    let mut first = 0;
    for (g, gen_spec) in sp.generations.iter().enumerate() {
        let parents: Vec<usize> = (first..branches.len()).collect();
        first = branches.len();
        for p in parents {
            let parent = branches[p].clone();
            let plen = parent.length();
            let pdir = parent.direction();
            let side = perpendicular(pdir);
            for c in 0..gen_spec.children {
                // Position along the parent, evenly spread past `start` with some jitter.
                let f = gen_spec.start
                    + (1.0 - gen_spec.start) * (c as f32 + 0.3 + 0.4 * rng.f32())
                        / gen_spec.children as f32;
                let s = f * parent.chain.bones.len() as f32;
                let origin = parent.chain.point(s);
                let azimuth = c as f32 * golden + rng.f32() * 0.5 + p as f32;
                let mut angle = gen_spec.angle + (rng.f32() - 0.5) * 12.0;
                let mut length = plen * gen_spec.length * (0.8 + 0.4 * rng.f32());
                if sp.conifer && g == 0 {
                    // Whorls: near-horizontal, shorter towards the top, drooping a little.
                    length = sp.height * gen_spec.length * (1.05 - f) * 1.25;
                    angle = gen_spec.angle - 25.0 * (1.0 - f);
                } else if !sp.conifer {
                    length *= 1.0 - 0.35 * f;
                }
                let axis = Quat::from_axis_angle(pdir, azimuth) * side;
                let mut dir = Quat::from_axis_angle(axis, angle.to_radians()) * pdir;
                if !sp.conifer {
                    // Broad-leaved branches reach for the light.
                    dir = (dir + Vec3::Y * 0.35 * g as f32 / 3.0).normalize();
                }
                let parent_bone =
                    parent.chain.bones[(s.floor() as usize).min(parent.chain.bones.len() - 1)];
                let mut bones = Vec::new();
                let mut points = vec![origin];
                let seg = length / gen_spec.segments as f32;
                let mut d = dir;
                for k in 0..gen_spec.segments {
                    let head = *points.last().unwrap();
                    let prev = bones.last().copied().unwrap_or(parent_bone);
                    bones.push(rig.bone(&format!("b{g}_{}_{k}", branches.len()), Some(prev), head));
                    // Gravity bends long branches down, light bends short ones up.
                    d = (d + Vec3::new(0.0, if sp.conifer { -0.12 } else { 0.06 }, 0.0))
                        .normalize();
                    points.push(head + d * seg);
                }
                let radius = parent.radius(s).min(parent.base_radius * 0.7) * 0.75;
                branches.push(Branch {
                    chain: Chain {
                        parent: Some(parent_bone),
                        bones,
                        points,
                    },
                    generation: g + 1,
                    base_radius: radius.max(0.008),
                    tip_radius: (radius * 0.35).max(0.005),
                });
            }
        }
    }
    branches
}

/// Appends a vertex with its weights.
fn push_vertex(
    mesh: &mut SkinnedMesh,
    p: Vec3,
    n: Vec3,
    uv: Vec2,
    material: u16,
    weights: &Weights,
) -> u32 {
    mesh.positions.push(p);
    mesh.normals.push(n);
    mesh.uvs.push(uv);
    mesh.materials.push(material);
    for &(bone, weight) in weights {
        mesh.influences.push(Influence { bone, weight });
    }
    mesh.influence_offsets.push(mesh.influences.len() as u32);
    mesh.positions.len() as u32 - 1
}

/// A closed tapering tube along a branch: rings every third of a bone, capped at both ends.
fn tube(mesh: &mut SkinnedMesh, b: &Branch) {
    let sides = match b.generation {
        0 => 10,
        1 => 7,
        2 => 5,
        _ => 4,
    };
    let per_bone = if b.generation == 0 { 4 } else { 3 };
    let rings = b.chain.bones.len() * per_bone;
    let dir = b.direction();
    let u_axis = perpendicular(dir);
    let v_axis = dir.cross(u_axis);
    let length = b.length();
    let circumference = std::f32::consts::TAU * b.base_radius.max(0.02);
    let mut ring_starts = Vec::new();
    for r in 0..=rings {
        let s = r as f32 / per_bone as f32;
        let centre = b.chain.point(s);
        // The base ring sits a little inside the parent, so the joint has no gap.
        let centre = if r == 0 && b.generation > 0 {
            centre - dir * b.base_radius * 0.6
        } else {
            centre
        };
        let radius = b.radius(s);
        let weights = b.chain.weights(s);
        ring_starts.push(mesh.positions.len() as u32);
        for k in 0..=sides {
            // The seam vertex (k = sides) repeats k = 0 exactly, with u = 1.
            let a = std::f32::consts::TAU * (k % sides) as f32 / sides as f32;
            let n = u_axis * a.cos() + v_axis * a.sin();
            let uv = Vec2::new(
                k as f32 / sides as f32,
                s / b.chain.bones.len() as f32 * length / circumference,
            );
            push_vertex(mesh, centre + n * radius, n, uv, BARK, &weights);
        }
    }
    for r in 0..rings {
        let (a, b0) = (ring_starts[r], ring_starts[r + 1]);
        for k in 0..sides as u32 {
            mesh.indices.extend_from_slice(&[
                a + k,
                a + k + 1,
                b0 + k + 1,
                a + k,
                b0 + k + 1,
                b0 + k,
            ]);
        }
    }
    // Caps: a fan from a centre vertex over the end ring's own vertices, so the tube stays one
    // chart in texture space (the cap a fan just beyond the ring's edge of the strip) and its
    // rings are no chart border: the simplifier may collapse them.
    for (end, s) in [(0usize, 0.0f32), (rings, rings as f32 / per_bone as f32)] {
        let normal = if end == 0 { -dir } else { dir };
        let ring = ring_starts[end];
        let centre =
            mesh.positions[ring as usize].lerp(mesh.positions[ring as usize + sides / 2], 0.5);
        let weights = b.chain.weights(s);
        let v_edge = mesh.uvs[ring as usize].y;
        let v_centre = if end == 0 {
            v_edge - 0.15
        } else {
            v_edge + 0.15
        };
        let c = push_vertex(
            mesh,
            centre,
            normal,
            Vec2::new(0.5, v_centre),
            BARK,
            &weights,
        );
        for k in 0..sides as u32 {
            let (p, q) = (ring + k, ring + k + 1);
            if end == 0 {
                mesh.indices.extend_from_slice(&[c, q, p]);
            } else {
                mesh.indices.extend_from_slice(&[c, p, q]);
            }
        }
    }
}

/// Leaf quads along every foliage-carrying bone, each bound to that bone alone.
fn foliage(mesh: &mut SkinnedMesh, sp: &Species, branches: &[Branch], rng: &mut fastrand::Rng) {
    for b in branches.iter().filter(|b| b.generation >= sp.foliage_from) {
        let n = b.chain.bones.len();
        let dir = b.direction();
        for (i, &bone) in b.chain.bones.iter().enumerate() {
            let weights: Weights = vec![(bone as u32, 1.0)];
            // Tips carry more than bases.
            let count = if sp.conifer || i + 1 == n {
                sp.leaves_per_bone
            } else {
                sp.leaves_per_bone / 2
            };
            for _ in 0..count {
                let s = i as f32 + rng.f32();
                let at = b.chain.point(s);
                // Spread round the branch, facing outwards and a little up.
                let around = Quat::from_axis_angle(dir, rng.f32() * std::f32::consts::TAU)
                    * perpendicular(dir);
                let reach = if sp.conifer {
                    0.05
                } else {
                    0.12 + 0.2 * rng.f32()
                };
                let base = at + around * (b.radius(s) + reach);
                let out = if sp.conifer {
                    // Needle sprays lie along the twig, roughly flat.
                    (dir + around * 0.4 + Vec3::Y * 0.1).normalize()
                } else {
                    (around + dir * 0.6 + Vec3::Y * 0.4).normalize()
                };
                let mut width_axis = out.cross(Vec3::Y).normalize_or(Vec3::X);
                let tilt = (rng.f32() - 0.5) * 1.4;
                width_axis = Quat::from_axis_angle(out, tilt) * width_axis;
                let size = sp.leaf_size * (0.75 + 0.5 * rng.f32());
                let normal = width_axis.cross(out).normalize();
                let normal = if normal.y < 0.0 { -normal } else { normal };
                let half = width_axis * size * 0.5;
                let tip = out * size;
                let corners = [
                    (base - half, Vec2::new(0.0, 1.0)),
                    (base + half, Vec2::new(1.0, 1.0)),
                    (base + half + tip, Vec2::new(1.0, 0.0)),
                    (base - half + tip, Vec2::new(0.0, 0.0)),
                ];
                let first = mesh.positions.len() as u32;
                for (p, uv) in corners {
                    push_vertex(mesh, p, normal, uv, FOLIAGE, &weights);
                }
                mesh.indices.extend_from_slice(&[
                    first,
                    first + 1,
                    first + 2,
                    first,
                    first + 2,
                    first + 3,
                ]);
            }
        }
    }
}

/// The looping wind clip.
fn wind(
    sp: &Species,
    rig: &Rig,
    branches: &[Branch],
    rng: &mut fastrand::Rng,
) -> crate::model::Clip {
    // Per bone: two bend axes across the branch, amplitudes (radians) and whole cycles per loop.
    struct Sway {
        bone: usize,
        axes: [Vec3; 2],
        amplitude: f32,
        cycles: [f32; 3],
        phases: [f32; 3],
    }
    let wind_dir = Vec3::new(1.0, 0.0, 0.35).normalize();
    let mut sways = Vec::new();
    for b in branches {
        let dir = b.direction();
        let across = perpendicular(dir);
        let other = dir.cross(across);
        for (i, &bone) in b.chain.bones.iter().enumerate() {
            let radius = b.radius(i as f32 + 0.5);
            // Thinner sways more: about 1° for the trunk, up to 9° for the thinnest twigs.
            let amplitude = (1.1f32 * (sp.trunk_radius / radius).powf(0.55))
                .min(9.0)
                .to_radians();
            // Deeper sways faster, in whole cycles per loop.
            let base = 2.0 + 2.0 * b.generation as f32;
            sways.push(Sway {
                bone,
                axes: [across, other],
                amplitude,
                cycles: [
                    base + rng.usize(0..2) as f32,
                    base + 1.0 + rng.usize(0..3) as f32,
                    base * 2.0 + rng.usize(0..3) as f32,
                ],
                phases: [rng.f32(), rng.f32(), rng.f32()],
            });
        }
    }
    let lean_axis = Vec3::Y.cross(wind_dir).normalize();
    let trunk_root = branches[0].chain.bones[0];
    bake_clip("wind", WIND_SECONDS, 0.0, rig, trunk_root, |phase| {
        let mut pose = Pose::rest(rig.len());
        for s in &sways {
            let a = s.amplitude;
            let bend0 = a
                * (0.7 * wave(phase, s.cycles[0], s.phases[0])
                    + 0.3 * wave(phase, s.cycles[2], s.phases[2]));
            let bend1 = a * 0.6 * wave(phase, s.cycles[1], s.phases[1]);
            let q =
                Quat::from_axis_angle(s.axes[0], bend0) * Quat::from_axis_angle(s.axes[1], bend1);
            pose.rotate(s.bone, q);
        }
        // The whole tree leans a little with the wind, gusting twice a loop.
        let gust = 0.012 * (1.0 + 0.5 * wave(phase, 2.0, 0.1));
        pose.rotate(trunk_root, Quat::from_axis_angle(lean_axis, gust));
        pose
    })
}

/// Bark: vertical fissures over a brown ground.
pub(crate) fn bark_texture() -> Rgba8Image {
    let size = TEXTURE_SIZE;
    let mut pixels = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let u = x as f32 / size as f32;
            let v = y as f32 / size as f32;
            let p = Vec3::new(
                (u * std::f32::consts::TAU).cos() * 2.0,
                (u * std::f32::consts::TAU).sin() * 2.0,
                v * 6.0,
            );
            let ridges = fbm(Vec3::new(p.x * 3.0, p.y * 3.0, p.z * 0.6));
            let fissure = smooth(0.42, 0.55, ridges);
            let grain = fbm(p * 5.0);
            let c = Vec3::new(0.30, 0.22, 0.15) * (0.55 + 0.6 * fissure) * (0.85 + 0.3 * grain);
            pixels.extend(srgb(c, 1.0));
        }
    }
    Rgba8Image {
        width: size,
        height: size,
        pixels,
    }
}

pub(crate) fn srgb(c: Vec3, a: f32) -> [u8; 4] {
    use crate::model::linear_to_srgb;
    [
        linear_to_srgb(c.x),
        linear_to_srgb(c.y),
        linear_to_srgb(c.z),
        (a.clamp(0.0, 1.0) * 255.0).round() as u8,
    ]
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: Vec2, a: Vec2, b: Vec2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// The foliage texture: a cluster of three leaves on short stalks (broadleaf), or a spray of
/// needles along a twig (conifer), with the shape in the alpha channel. The quad's base edge is
/// at the bottom of the texture (v = 1), where the cluster attaches.
pub(crate) fn foliage_texture(conifer: bool) -> Rgba8Image {
    let size = TEXTURE_SIZE;
    let mut pixels = Vec::with_capacity((size * size * 4) as usize);
    let base = Vec2::new(0.5, 0.98);
    for y in 0..size {
        for x in 0..size {
            let p = Vec2::new(
                (x as f32 + 0.5) / size as f32,
                (y as f32 + 0.5) / size as f32,
            );
            let (mut alpha, mut colour) = (0.0f32, Vec3::ZERO);
            let shade = fbm(Vec3::new(
                p.x * 9.0,
                p.y * 9.0,
                if conifer { 3.0 } else { 1.0 },
            ));
            if conifer {
                // A spray: a twig up the middle in a tapering mass of needles slanting off both
                // sides, the edge serrated by the needle tips. Solid enough to keep its shape
                // at a distance; the needles show in the colour and the edge.
                let along = ((0.98 - p.y) / 0.94).clamp(0.0, 1.0);
                let across = (p.x - 0.5).abs();
                let half =
                    0.4 * (std::f32::consts::PI * along.powf(0.7)).sin() * (1.0 - 0.45 * along);
                let tips = (across * 18.0 + along * 30.0).fract();
                let edge = half * (0.78 + 0.22 * (1.0 - (2.0 * tips - 1.0).abs()));
                if across < 0.012 && along > 0.0 && along < 0.97 {
                    alpha = 1.0;
                    colour = Vec3::new(0.25, 0.17, 0.1);
                } else if across <= edge && p.y <= 0.98 {
                    alpha = 1.0;
                    let needle = ((across * 1.3 + (0.98 - p.y) * 0.75) * 45.0).fract();
                    let stripe =
                        0.75 + 0.35 * smooth(0.2, 0.5, needle) * (1.0 - smooth(0.5, 0.8, needle));
                    colour = Vec3::new(0.05, 0.16, 0.07) * stripe * (0.8 + 0.4 * shade);
                }
            } else {
                // Three ovate leaves fanning out from the base.
                for (angle, len) in [(-0.62f32, 0.5f32), (0.0, 0.62), (0.6, 0.48)] {
                    let dir = Vec2::new(angle.sin(), -angle.cos());
                    let stalk = base + dir * 0.1;
                    let q = p - stalk;
                    let along = q.dot(dir) / len;
                    let across = q.perp_dot(dir) / len;
                    // A leaf: widest a third of the way, pointed at the tip.
                    let half_width = 0.3
                        * (along.clamp(0.0, 1.0) * std::f32::consts::PI)
                            .sin()
                            .powf(0.8)
                        * (1.0 - along).clamp(0.0, 1.0).powf(0.3);
                    if (0.0..=1.0).contains(&along) && across.abs() <= half_width {
                        alpha = 1.0;
                        let vein = 1.0 - smooth(0.0, 0.025, across.abs()) * 0.25;
                        let edge = 1.0 - 0.25 * (across.abs() / half_width.max(1e-3));
                        colour = Vec3::new(0.16, 0.36, 0.08) * (0.7 + 0.5 * shade) * edge
                            + Vec3::new(0.05, 0.06, 0.0) * (1.0 - vein) * 4.0;
                    } else if segment_distance(p, base, stalk) < 0.01 {
                        alpha = 1.0;
                        colour = Vec3::new(0.22, 0.3, 0.08);
                    }
                }
            }
            pixels.extend(srgb(colour, alpha));
        }
    }
    Rgba8Image {
        width: size,
        height: size,
        pixels,
    }
}

fn build(sp: &Species) -> Model {
    let mut rng = fastrand::Rng::with_seed(sp.seed);
    let mut rig = Rig::default();
    let branches = grow(sp, &mut rig, &mut rng);
    let mut mesh = SkinnedMesh::default();
    mesh.influence_offsets.push(0);
    for b in &branches {
        tube(&mut mesh, b);
    }
    foliage(&mut mesh, sp, &branches, &mut rng);
    let clip = wind(sp, &rig, &branches, &mut rng);
    Model {
        name: sp.name.into(),
        mesh,
        skeleton: rig.skeleton(),
        clips: vec![clip],
        materials: vec![
            Material::opaque("bark", [1.0; 4], Some(bark_texture())),
            Material::cut_out(
                if sp.conifer { "needles" } else { "leaves" },
                [1.0; 4],
                Some(foliage_texture(sp.conifer)),
            ),
        ],
    }
}

/// A broad-leaved tree about 7 m tall.
pub fn broadleaf() -> Model {
    build(&broadleaf_species())
}

/// The broad-leaved tree with `leaves_per_bone` leaf quads on each twig bone instead of 42
/// (93 gives about 10,000 leaves): for timing bakes at a given leaf count. Not an asset.
pub fn dense_broadleaf(leaves_per_bone: usize) -> Model {
    build(&Species {
        name: "broadleaf-dense",
        leaves_per_bone,
        ..broadleaf_species()
    })
}

/// A broad-leaved sapling about 4 m tall, with 672 leaf quads: the size of the thesis's tree.
pub fn sapling() -> Model {
    build(&sapling_species())
}

/// A conifer about 10 m tall.
pub fn conifer() -> Model {
    build(&conifer_species())
}

/// Which material of a generated tree is foliage.
pub const FOLIAGE_MATERIAL: u16 = FOLIAGE;
