//! "armour": a test model with the properties of kit-bashed game characters that the demo
//! creatures lack: a knight of 57 separate closed parts (plates, limb shells, rings, pads and
//! two dozen rivets) on 18 joints, with hard edges on its boxes and pad rims, and no texture
//! coordinates at all. The parts overlap without sharing a vertex, as parts modelled apart do.
//! One clip, `walk`.
//!
//! Metres, facing +z, standing on y = 0, left side at +x.

use super::cage::Weights;
use super::facets::{FacetBuilder, normalised};
use super::rig::{Chain, Pose, Rig, bake_clip, bump, euler, rigid};
use crate::model::{Clip, Material, Model};
use glam::{Quat, Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// Shapes, each added as one closed part.
struct Parts {
    b: FacetBuilder,
    next_group: u32,
    /// Tessellation relative to the asset's: segments round every shape are multiplied by it.
    detail: f32,
}

impl Parts {
    /// `n` segments at this detail.
    fn n(&self, n: usize) -> usize {
        ((n as f32 * self.detail).round() as usize).max(3)
    }

    fn group(&mut self) -> u32 {
        self.next_group += 1;
        self.next_group
    }

    /// A smooth ellipsoid of `slices` × `stacks`, its axes turned by `turn`; `weights` gives
    /// each point its skin weights.
    fn ellipsoid(
        &mut self,
        centre: Vec3,
        radii: Vec3,
        turn: Quat,
        (slices, stacks): (usize, usize),
        weights: &dyn Fn(Vec3) -> Weights,
    ) {
        let (slices, stacks) = (self.n(slices), self.n(stacks));
        let g = self.group();
        let at = |theta: f32, phi: f32| {
            let d = Vec3::new(phi.sin() * theta.cos(), phi.cos(), -phi.sin() * theta.sin());
            centre + turn * (d * radii)
        };
        let point = |b: &mut FacetBuilder, p: Vec3| b.point(p, weights(p));
        let top = point(&mut self.b, at(0.0, 0.0));
        let bottom = point(&mut self.b, at(0.0, PI));
        let rows: Vec<Vec<u32>> = (1..stacks)
            .map(|i| {
                let phi = PI * i as f32 / stacks as f32;
                (0..slices)
                    .map(|j| point(&mut self.b, at(TAU * j as f32 / slices as f32, phi)))
                    .collect()
            })
            .collect();
        for j in 0..slices {
            let j1 = (j + 1) % slices;
            self.b
                .triangle([top, rows[0][j], rows[0][j1]], g, [Vec2::ZERO; 3]);
            let last = &rows[stacks - 2];
            self.b
                .triangle([bottom, last[j1], last[j]], g, [Vec2::ZERO; 3]);
            for i in 0..stacks - 2 {
                let (r0, r1) = (&rows[i], &rows[i + 1]);
                self.b
                    .quad([r0[j], r1[j], r1[j1], r0[j1]], g, [Vec2::ZERO; 4]);
            }
        }
    }

    /// A limb shell: an ellipsoid from `a` to `b` of radius `r`, skinned along `chain` between
    /// chain coordinates `s0` and `s1`.
    fn shell(&mut self, a: Vec3, b: Vec3, r: f32, chain: &Chain, (s0, s1): (f32, f32)) {
        let axis = b - a;
        let turn = Quat::from_rotation_arc(Vec3::Y, axis.normalize());
        let len = axis.length();
        self.ellipsoid(
            (a + b) * 0.5,
            Vec3::new(r, 0.5 * len + 0.3 * r, r),
            turn,
            (18, 12),
            &|p| {
                let t = ((p - a).dot(axis) / (len * len)).clamp(0.0, 1.0);
                normalised(chain.weights(s0 + t * (s1 - s0)))
            },
        );
    }

    /// A dome (half an ellipsoid, its rim on the plane through `centre` across `up`) closed by a
    /// flat base: the rim is a hard edge.
    fn dome(&mut self, centre: Vec3, radii: Vec3, up: Vec3, bone: usize) {
        let turn = Quat::from_rotation_arc(Vec3::Y, up.normalize());
        let (slices, stacks) = (self.n(20), self.n(6));
        let (g, base) = (self.group(), self.group());
        let at = |theta: f32, phi: f32| {
            let d = Vec3::new(phi.sin() * theta.cos(), phi.cos(), -phi.sin() * theta.sin());
            centre + turn * (d * radii)
        };
        let w = rigid(bone);
        let top = self.b.point(at(0.0, 0.0), w.clone());
        let rows: Vec<Vec<u32>> = (1..=stacks)
            .map(|i| {
                let phi = 0.5 * PI * i as f32 / stacks as f32;
                (0..slices)
                    .map(|j| {
                        self.b
                            .point(at(TAU * j as f32 / slices as f32, phi), w.clone())
                    })
                    .collect()
            })
            .collect();
        let middle = self.b.point(centre, w.clone());
        for j in 0..slices {
            let j1 = (j + 1) % slices;
            self.b
                .triangle([top, rows[0][j], rows[0][j1]], g, [Vec2::ZERO; 3]);
            for i in 0..stacks - 1 {
                let (r0, r1) = (&rows[i], &rows[i + 1]);
                self.b
                    .quad([r0[j], r1[j], r1[j1], r0[j1]], g, [Vec2::ZERO; 4]);
            }
            let rim = &rows[stacks - 1];
            self.b
                .triangle([middle, rim[j1], rim[j]], base, [Vec2::ZERO; 3]);
        }
    }

    /// A smooth torus round `axis`.
    fn torus(&mut self, centre: Vec3, axis: Vec3, major: f32, minor: f32, bone: usize) {
        let turn = Quat::from_rotation_arc(Vec3::Y, axis.normalize());
        let (segments, sides) = (self.n(22), self.n(8));
        let g = self.group();
        let w = rigid(bone);
        let ids: Vec<Vec<u32>> = (0..segments)
            .map(|i| {
                let a = TAU * i as f32 / segments as f32;
                let radial = Vec3::new(a.cos(), 0.0, -a.sin());
                (0..sides)
                    .map(|k| {
                        let b = TAU * k as f32 / sides as f32;
                        let p = radial * (major + minor * b.cos()) + Vec3::Y * minor * b.sin();
                        self.b.point(centre + turn * p, w.clone())
                    })
                    .collect()
            })
            .collect();
        for i in 0..segments {
            let i1 = (i + 1) % segments;
            for k in 0..sides {
                let k1 = (k + 1) % sides;
                self.b.quad(
                    [ids[i][k], ids[i1][k], ids[i1][k1], ids[i][k1]],
                    g,
                    [Vec2::ZERO; 4],
                );
            }
        }
    }

    /// A box with hard edges, each face a grid of `n` × `n` quads.
    fn cuboid(&mut self, centre: Vec3, half: Vec3, turn: Quat, n: usize, bone: usize) {
        let w = rigid(bone);
        let mut ids: std::collections::HashMap<(i32, i32, i32), u32> = Default::default();
        let n = ((n as f32 * self.detail).round() as i32).max(1);
        for axis in 0..3 {
            for sign in [-1i32, 1] {
                let g = self.group();
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let mut grid = vec![vec![0u32; n as usize + 1]; n as usize + 1];
                for (a, row) in grid.iter_mut().enumerate() {
                    for (c, id) in row.iter_mut().enumerate() {
                        let mut k = [0i32; 3];
                        k[axis] = sign * n;
                        k[u] = 2 * a as i32 - n;
                        k[v] = 2 * c as i32 - n;
                        let key = (k[0], k[1], k[2]);
                        *id = *ids.entry(key).or_insert_with(|| {
                            let unit = Vec3::new(k[0] as f32, k[1] as f32, k[2] as f32) / n as f32;
                            self.b.point(centre + turn * (unit * half), w.clone())
                        });
                    }
                }
                for a in 0..n as usize {
                    for c in 0..n as usize {
                        let q = [
                            grid[a][c],
                            grid[a + 1][c],
                            grid[a + 1][c + 1],
                            grid[a][c + 1],
                        ];
                        let q = if sign > 0 {
                            q
                        } else {
                            [q[0], q[3], q[2], q[1]]
                        };
                        self.b.quad(q, g, [Vec2::ZERO; 4]);
                    }
                }
            }
        }
    }

    /// A rivet: a small sphere half sunk into the surface at `at`, facing `out`.
    fn rivet(&mut self, at: Vec3, bone: usize) {
        let w = rigid(bone);
        self.ellipsoid(at, Vec3::splat(0.011), Quat::IDENTITY, (8, 5), &|_| {
            w.clone()
        });
    }
}

/// The point of the ellipsoid (`centre`, `radii`) in direction `d`.
fn on_ellipsoid(centre: Vec3, radii: Vec3, d: Vec3) -> Vec3 {
    centre + d / (d / radii).length()
}

pub fn armour() -> Model {
    armour_at(1.0)
}

/// The same knight with every shape's segments multiplied by `detail` (triangles grow with
/// its square): at 2.25, about 60,000 triangles, for benchmarks.
pub fn armour_at(detail: f32) -> Model {
    let k = knight(detail);
    Model {
        name: "armour".into(),
        mesh: k.parts.build(0.0),
        skeleton: k.rig.skeleton(),
        clips: vec![k.walk],
        materials: vec![Material::opaque("steel", [0.62, 0.64, 0.68, 1.0], None)],
    }
}

/// The knight before it is a model: its parts (each smoothing group one shape, or one face of
/// a box), its rig and its walk, and the bones a prop would hang from.
pub(crate) struct Knight {
    pub parts: FacetBuilder,
    pub rig: Rig,
    pub walk: crate::model::Clip,
    /// The right hand and the chest.
    pub hand_r: usize,
    pub chest: usize,
}

/// The knight's joints: the rig, and the bones the parts and the walk refer to by name.
struct Bones {
    rig: Rig,
    root: usize,
    hips: usize,
    spine: usize,
    chest: usize,
    neck: usize,
    head: usize,
    /// Upper arm, forearm and hand, left then right.
    arms: [[usize; 3]; 2],
    /// Thigh, shin and foot, left then right.
    legs: [[usize; 3]; 2],
}

/// The chest plate's and the helmet's ellipsoids (centre, radii), shared by the plates and the
/// rivets set into them.
const CHEST_SHELL: (Vec3, Vec3) = (Vec3::new(0.0, 1.32, 0.01), Vec3::new(0.19, 0.15, 0.12));
const HEAD_SHELL: (Vec3, Vec3) = (Vec3::new(0.0, 1.64, 0.01), Vec3::new(0.1, 0.12, 0.11));

/// The 18 joints: the trunk from root to head, then each side's arm and leg (left first).
fn knight_rig() -> Bones {
    let mut r = Rig::default();
    let root = r.bone("root", None, Vec3::ZERO);
    let hips = r.bone("hips", Some(root), Vec3::new(0.0, 0.95, 0.0));
    let spine = r.bone("spine", Some(hips), Vec3::new(0.0, 1.08, 0.0));
    let chest = r.bone("chest", Some(spine), Vec3::new(0.0, 1.25, 0.0));
    let neck = r.bone("neck", Some(chest), Vec3::new(0.0, 1.48, 0.0));
    let head = r.bone("head", Some(neck), Vec3::new(0.0, 1.56, 0.0));
    let mut arms = [[0usize; 3]; 2];
    let mut legs = [[0usize; 3]; 2];
    for (i, (side, x)) in [("l", 1.0f32), ("r", -1.0)].into_iter().enumerate() {
        let a = r.bone(
            &format!("upper_arm_{side}"),
            Some(chest),
            Vec3::new(0.22 * x, 1.42, 0.0),
        );
        let b = r.bone(
            &format!("forearm_{side}"),
            Some(a),
            Vec3::new(0.27 * x, 1.14, 0.0),
        );
        let c = r.bone(
            &format!("hand_{side}"),
            Some(b),
            Vec3::new(0.30 * x, 0.88, 0.0),
        );
        arms[i] = [a, b, c];
        let a = r.bone(
            &format!("thigh_{side}"),
            Some(hips),
            Vec3::new(0.1 * x, 0.9, 0.0),
        );
        let b = r.bone(
            &format!("shin_{side}"),
            Some(a),
            Vec3::new(0.1 * x, 0.5, 0.0),
        );
        let c = r.bone(
            &format!("foot_{side}"),
            Some(b),
            Vec3::new(0.1 * x, 0.1, 0.0),
        );
        legs[i] = [a, b, c];
    }
    Bones {
        rig: r,
        root,
        hips,
        spine,
        chest,
        neck,
        head,
        arms,
        legs,
    }
}

/// The trunk's parts: pelvis, waist, chest and neck plates skinned along the spine (so they
/// bend with it), the helmet with its crest and visor, and the belt with its buckle.
fn trunk_parts(p: &mut Parts, k: &Bones) {
    let (r, hips, head) = (&k.rig, k.hips, k.head);
    let trunk = Chain::new(
        r,
        &[k.hips, k.spine, k.chest, k.neck, k.head],
        Vec3::new(0.0, 1.78, 0.0),
    );
    let on_trunk = |s0: f32, s1: f32, y0: f32, y1: f32| {
        let trunk = trunk.clone();
        move |q: Vec3| {
            let t = ((q.y - y0) / (y1 - y0)).clamp(0.0, 1.0);
            normalised(trunk.weights(s0 + t * (s1 - s0)))
        }
    };
    let (pelvis_c, pelvis_r) = (Vec3::new(0.0, 0.97, 0.0), Vec3::new(0.16, 0.1, 0.11));
    let (chest_c, chest_r) = CHEST_SHELL;
    let (head_c, head_r) = HEAD_SHELL;
    p.ellipsoid(
        pelvis_c,
        pelvis_r,
        Quat::IDENTITY,
        (26, 14),
        &on_trunk(0.3, 0.7, 0.87, 1.07),
    );
    p.ellipsoid(
        Vec3::new(0.0, 1.12, 0.0),
        Vec3::new(0.14, 0.09, 0.1),
        Quat::IDENTITY,
        (24, 12),
        &on_trunk(0.7, 1.6, 1.03, 1.21),
    );
    p.ellipsoid(
        chest_c,
        chest_r,
        Quat::IDENTITY,
        (26, 14),
        &on_trunk(1.6, 2.6, 1.17, 1.47),
    );
    p.ellipsoid(
        Vec3::new(0.0, 1.5, 0.0),
        Vec3::new(0.05, 0.06, 0.05),
        Quat::IDENTITY,
        (14, 8),
        &on_trunk(2.8, 3.4, 1.44, 1.56),
    );
    p.ellipsoid(head_c, head_r, Quat::IDENTITY, (26, 14), &|_| rigid(head));
    p.cuboid(
        Vec3::new(0.0, 1.75, -0.01),
        Vec3::new(0.012, 0.04, 0.1),
        Quat::IDENTITY,
        3,
        head,
    );
    p.cuboid(
        Vec3::new(0.0, 1.655, 0.105),
        Vec3::new(0.075, 0.018, 0.02),
        Quat::from_rotation_x(0.15),
        1,
        head,
    );
    p.torus(Vec3::new(0.0, 1.03, 0.0), Vec3::Y, 0.155, 0.022, hips);
    p.cuboid(
        Vec3::new(0.0, 1.03, 0.175),
        Vec3::new(0.035, 0.028, 0.012),
        Quat::IDENTITY,
        1,
        hips,
    );
}

/// One side's parts (`i` 0 left, 1 right; `x` the side's sign): the arm's shells, shoulder
/// pad, rings and gauntlet, the leg's shells, knee pad, rings and boot, then the side's rivets
/// on the pads and the helmet.
fn side_parts(p: &mut Parts, bones: &Bones, i: usize, x: f32) {
    let (r, head) = (&bones.rig, bones.head);
    let (head_c, head_r) = HEAD_SHELL;
    let [ua, fa, hand] = bones.arms[i];
    let [th, sh, ft] = bones.legs[i];
    let shoulder = Vec3::new(0.22 * x, 1.42, 0.0);
    let elbow = Vec3::new(0.27 * x, 1.14, 0.0);
    let wrist = Vec3::new(0.3 * x, 0.88, 0.0);
    let arm = Chain::new(r, &[ua, fa, hand], Vec3::new(0.31 * x, 0.74, 0.0));
    p.shell(shoulder, elbow, 0.05, &arm, (0.0, 1.0));
    p.shell(elbow, wrist, 0.045, &arm, (1.0, 2.0));
    let pad_c = Vec3::new(0.23 * x, 1.44, 0.0);
    let pad_r = Vec3::new(0.1, 0.07, 0.1);
    let pad_up = Vec3::new(0.35 * x, 1.0, 0.0);
    p.dome(pad_c, pad_r, pad_up, ua);
    p.torus(elbow, elbow - shoulder, 0.056, 0.014, fa);
    p.torus(
        wrist + (wrist - elbow) * 0.05,
        wrist - elbow,
        0.05,
        0.012,
        hand,
    );
    p.cuboid(
        Vec3::new(0.305 * x, 0.81, 0.0),
        Vec3::new(0.025, 0.07, 0.045),
        Quat::IDENTITY,
        2,
        hand,
    );
    let hip = Vec3::new(0.1 * x, 0.9, 0.0);
    let knee = Vec3::new(0.1 * x, 0.5, 0.0);
    let ankle = Vec3::new(0.1 * x, 0.1, 0.0);
    let leg = Chain::new(r, &[th, sh, ft], Vec3::new(0.1 * x, 0.03, 0.16));
    p.shell(hip, knee, 0.075, &leg, (0.0, 1.0));
    p.shell(knee, ankle, 0.06, &leg, (1.0, 2.0));
    let knee_pad = (Vec3::new(0.1 * x, 0.5, 0.065), Vec3::new(0.06, 0.035, 0.06));
    p.dome(knee_pad.0, knee_pad.1, Vec3::Z, sh);
    p.torus(knee - Vec3::Y * 0.06, Vec3::Y, 0.068, 0.013, sh);
    p.torus(ankle + Vec3::Y * 0.03, Vec3::Y, 0.056, 0.012, sh);
    p.cuboid(
        Vec3::new(0.1 * x, 0.045, 0.05),
        Vec3::new(0.05, 0.045, 0.11),
        Quat::IDENTITY,
        2,
        ft,
    );
    // Rivets: three on the pad, two on the knee pad, one on each side of the helmet.
    let turn = Quat::from_rotation_arc(Vec3::Y, pad_up.normalize());
    for k in 0..3 {
        let a = TAU * k as f32 / 3.0 + 0.4;
        let d = turn * Vec3::new(a.cos(), 0.5, a.sin());
        p.rivet(on_ellipsoid(pad_c, turn * pad_r, d), ua);
    }
    for k in [-1.0f32, 1.0] {
        let d = Vec3::new(0.6 * k, 0.0, 1.0);
        p.rivet(on_ellipsoid(knee_pad.0, knee_pad.1, d), sh);
    }
    p.rivet(on_ellipsoid(head_c, head_r, Vec3::new(x, 0.0, 0.1)), head);
}

/// The rivets on the front: a zigzag of six across the chest plate, each followed by one of the
/// six round the back of the belt.
fn trunk_rivets(p: &mut Parts, bones: &Bones) {
    let (chest, hips) = (bones.chest, bones.hips);
    let (chest_c, chest_r) = CHEST_SHELL;
    // Rivets: six across the chest, six round the belt.
    for k in 0..6 {
        let a = (k as f32 - 2.5) * 0.28;
        let y = if k % 2 == 0 { 0.0 } else { 0.35 };
        let d = Vec3::new(a.sin(), y, a.cos());
        p.rivet(on_ellipsoid(chest_c, chest_r, d), chest);
        let a = (k as f32 - 2.5) * 0.7 + PI;
        let ring = Vec3::new(0.0, 1.03, 0.0) + Vec3::new(a.sin(), 0.0, a.cos()) * 0.178;
        p.rivet(ring, hips);
    }
}

/// The `walk` clip: legs and arms swinging half a cycle apart, spine and chest twisting, the
/// root bobbing twice a cycle.
fn walk(k: &Bones) -> Clip {
    let (r, root, spine, chest, arms, legs) = (&k.rig, k.root, k.spine, k.chest, k.arms, k.legs);
    bake_clip("walk", 1.2, 1.2, r, root, |ph| {
        let mut pose = Pose::rest(r.len());
        for i in 0..2 {
            let q = (ph + 0.5 * i as f32).rem_euclid(1.0);
            let hip = 24.0 * (TAU * q).cos();
            let knee = 10.0 * bump(q, 0.1, 0.12) + 55.0 * bump(q, 0.72, 0.2);
            let [th, sh, ft] = legs[i];
            pose.rotate(th, euler(-hip, 0.0, 0.0));
            pose.rotate(sh, euler(knee, 0.0, 0.0));
            pose.rotate(ft, euler(-8.0 * bump(q, 0.57, 0.1), 0.0, 0.0));
            let [ua, fa, _] = arms[i];
            pose.rotate(ua, euler(22.0 * (TAU * q).cos(), 0.0, 0.0));
            pose.rotate(fa, euler(-25.0 - 15.0 * (TAU * q).cos(), 0.0, 0.0));
        }
        pose.rotate(spine, euler(0.0, 8.0 * (TAU * ph).cos(), 0.0));
        pose.rotate(chest, euler(0.0, 6.0 * (TAU * ph).cos(), 0.0));
        pose.root_offset = Vec3::Y * (0.025 * (2.0 * TAU * ph).cos() - 0.02);
        pose
    })
}

pub(crate) fn knight(detail: f32) -> Knight {
    let bones = knight_rig();
    let mut p = Parts {
        b: FacetBuilder::default(),
        next_group: 0,
        detail,
    };
    trunk_parts(&mut p, &bones);
    for (i, x) in [1.0f32, -1.0].into_iter().enumerate() {
        side_parts(&mut p, &bones, i, x);
    }
    trunk_rivets(&mut p, &bones);

    let walk = walk(&bones);
    Knight {
        parts: p.b,
        hand_r: bones.arms[1][2],
        chest: bones.chest,
        rig: bones.rig,
        walk,
    }
}
