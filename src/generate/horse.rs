//! "horse": a bay quadruped, 27 bones, legs of three segments plus the hoof, neck, head with
//! ears, and a tail. Clips: `walk` (four-beat lateral sequence) and `gallop` (transverse).
//!
//! Metres, facing +z, standing on y = 0, left side at +x.

use super::build::{
    DECAGON, Section, assemble, body_rings, extrude_limb, extrude_rigid, limb,
    nearest_surface_point, section,
};
use super::cage::{Cage, Cap};
use super::finish::{fbm, noise, smooth};
use super::rig::{Chain, Pose, Rig, bake_clip, bump, euler, rigid, wave};
use crate::model::Model;
use glam::{Vec2, Vec3};

// Parts, for the painter.
const BODY: u32 = 0;
const NECK: u32 = 1;
const HEAD: u32 = 2;
const LEG: u32 = 3;
const HOOF: u32 = 4;
const EAR: u32 = 5;
const TAIL: u32 = 6;
const REAR: u32 = 7;
const NOSE: u32 = 8;

struct Legs {
    /// Bones of each leg, top to bottom: [front left, front right, hind left, hind right].
    bones: [[usize; 4]; 4],
    ends: [Vec3; 4],
}

fn rig() -> (Rig, Legs) {
    let mut r = Rig::default();
    let pelvis = r.bone("pelvis", None, Vec3::new(0.0, 1.22, -0.62));
    let spine1 = r.bone("spine1", Some(pelvis), Vec3::new(0.0, 1.26, -0.25));
    let spine2 = r.bone("spine2", Some(spine1), Vec3::new(0.0, 1.28, 0.15));
    let chest = r.bone("chest", Some(spine2), Vec3::new(0.0, 1.27, 0.52));
    let neck1 = r.bone("neck1", Some(chest), Vec3::new(0.0, 1.36, 0.82));
    let neck2 = r.bone("neck2", Some(neck1), Vec3::new(0.0, 1.56, 0.97));
    r.bone("head", Some(neck2), Vec3::new(0.0, 1.78, 1.10));
    let t1 = r.bone("tail1", Some(pelvis), Vec3::new(0.0, 1.30, -0.98));
    let t2 = r.bone("tail2", Some(t1), Vec3::new(0.0, 1.16, -1.10));
    let t3 = r.bone("tail3", Some(t2), Vec3::new(0.0, 0.96, -1.17));
    r.bone("tail4", Some(t3), Vec3::new(0.0, 0.76, -1.20));
    let mut bones = [[0; 4]; 4];
    let mut ends = [Vec3::ZERO; 4];
    for (i, (side, x)) in [("l", 0.19f32), ("r", -0.19)].into_iter().enumerate() {
        let a = r.bone(
            &format!("upper_arm_{side}"),
            Some(chest),
            Vec3::new(x, 1.10, 0.62),
        );
        let b = r.bone(
            &format!("forearm_{side}"),
            Some(a),
            Vec3::new(x, 0.80, 0.52),
        );
        let c = r.bone(
            &format!("front_cannon_{side}"),
            Some(b),
            Vec3::new(x, 0.46, 0.54),
        );
        let d = r.bone(
            &format!("front_pastern_{side}"),
            Some(c),
            Vec3::new(x, 0.15, 0.55),
        );
        bones[i] = [a, b, c, d];
        ends[i] = Vec3::new(x, 0.0, 0.60);
        let a = r.bone(
            &format!("thigh_{side}"),
            Some(pelvis),
            Vec3::new(x, 1.10, -0.60),
        );
        let b = r.bone(
            &format!("gaskin_{side}"),
            Some(a),
            Vec3::new(x, 0.80, -0.44),
        );
        let c = r.bone(
            &format!("hind_cannon_{side}"),
            Some(b),
            Vec3::new(x, 0.52, -0.70),
        );
        let d = r.bone(
            &format!("hind_pastern_{side}"),
            Some(c),
            Vec3::new(x, 0.15, -0.66),
        );
        bones[2 + i] = [a, b, c, d];
        ends[2 + i] = Vec3::new(x, 0.0, -0.61);
    }
    (r, Legs { bones, ends })
}

/// Cross-sections from the rump, along the barrel, up the neck and down the head.
const SECTIONS: [Section; 19] = [
    section(0.0, 1.22, -1.03, 0.12, 0.13),
    section(0.0, 1.20, -0.93, 0.22, 0.24),
    section(0.0, 1.17, -0.76, 0.27, 0.31),
    section(0.0, 1.15, -0.50, 0.28, 0.33),
    section(0.0, 1.14, -0.20, 0.29, 0.34),
    section(0.0, 1.15, 0.10, 0.30, 0.35),
    section(0.0, 1.17, 0.36, 0.29, 0.36),
    section(0.0, 1.19, 0.50, 0.27, 0.36),
    section(0.0, 1.23, 0.72, 0.23, 0.33),
    // Neck.
    section(0.0, 1.41, 0.88, 0.14, 0.24),
    section(0.0, 1.57, 0.98, 0.11, 0.18),
    section(0.0, 1.71, 1.05, 0.095, 0.14),
    // Head: poll, forehead, cheek, face, muzzle, nose.
    section(0.0, 1.83, 1.10, 0.10, 0.13),
    section(0.0, 1.82, 1.22, 0.125, 0.16),
    section(0.0, 1.72, 1.34, 0.115, 0.16),
    section(0.0, 1.60, 1.46, 0.09, 0.12),
    section(0.0, 1.50, 1.56, 0.08, 0.10),
    section(0.0, 1.44, 1.64, 0.085, 0.095),
    section(0.0, 1.40, 1.69, 0.065, 0.065),
];
const NECK_START: usize = 8;
const HEAD_START: usize = 12;
/// The ring segment the front and hind legs hang from, and the one the ears grow from.
const FRONT_LEG_SEGMENT: usize = 7;
const HIND_LEG_SEGMENT: usize = 2;
const EAR_SEGMENT: usize = 12;

fn cage(r: &Rig, legs: &Legs) -> Cage {
    let spine_bones: Vec<usize> = [
        "pelvis", "spine1", "spine2", "chest", "neck1", "neck2", "head",
    ]
    .iter()
    .map(|n| r.index(n))
    .collect();
    let spine = Chain::new(r, &spine_bones, Vec3::new(0.0, 1.40, 1.68));
    let mut cage = Cage::default();
    let tube = cage.tube(
        &body_rings(&SECTIONS, &DECAGON, Vec3::X, &spine),
        &[(0, BODY), (NECK_START, NECK), (HEAD_START, HEAD)],
        Cap {
            offset: 0,
            part: REAR,
        },
        Cap {
            offset: 0,
            part: NOSE,
        },
    );

    // Legs, from the lower diagonal faces of the barrel.
    // Catmull–Clark shrinks a four-sided tube to about two thirds of its cage: sizes allow
    // for that.
    // The visible leg starts at the elbow (front) and the stifle (hind); above them the limb is
    // inside the barrel.
    let front = [
        limb(0.97, 0.11, 0.135),
        limb(1.15, 0.095, 0.115),
        limb(1.4, 0.085, 0.097),
        limb(1.8, 0.066, 0.074),
        limb(2.0, 0.07, 0.08),
        limb(2.2, 0.056, 0.062),
        limb(2.6, 0.05, 0.056),
        limb(2.95, 0.062, 0.068),
        limb(3.35, 0.054, 0.06),
        limb(3.72, 0.072, 0.08),
        limb(3.97, 0.08, 0.09),
    ];
    let hind = [
        limb(0.95, 0.115, 0.17),
        limb(1.15, 0.097, 0.135),
        limb(1.45, 0.08, 0.105),
        limb(1.85, 0.062, 0.08),
        limb(2.0, 0.066, 0.092),
        limb(2.2, 0.056, 0.064),
        limb(2.6, 0.05, 0.056),
        limb(2.95, 0.062, 0.068),
        limb(3.35, 0.054, 0.06),
        limb(3.72, 0.072, 0.08),
        limb(3.97, 0.08, 0.09),
    ];
    for (i, bones) in legs.bones.iter().enumerate() {
        let x = if i % 2 == 0 { 1.0 } else { -1.0 };
        let segment = if i < 2 {
            FRONT_LEG_SEGMENT
        } else {
            HIND_LEG_SEGMENT
        };
        let face = cage.face_towards(&tube.sides[segment], Vec3::new(x * 0.4, -1.0, 0.0));
        let chain = Chain::new(r, bones, legs.ends[i]);
        let rings = if i < 2 { &front[..] } else { &hind[..] };
        extrude_limb(&mut cage, face, &chain, rings, Vec3::X, LEG, HOOF);
    }

    // Ears, from the upper diagonal faces behind the poll.
    let head = rigid(r.index("head"));
    for x in [1.0f32, -1.0] {
        let face = cage.face_towards(&tube.sides[EAR_SEGMENT], Vec3::new(x * 0.8, 1.0, 0.0));
        let c = cage.face_center(face);
        let out = Vec3::new(x * 0.35, 1.0, -0.15).normalize();
        extrude_rigid(
            &mut cage,
            face,
            &[
                (c + out * 0.07, Vec2::new(0.055, 0.03)),
                (c + out * 0.16, Vec2::new(0.048, 0.022)),
                (c + out * 0.24, Vec2::new(0.024, 0.012)),
                (c + out * 0.28, Vec2::new(0.006, 0.004)),
            ],
            &head,
            Vec3::Z,
            EAR,
            EAR,
        );
    }

    // Tail, from the top of the rump.
    let tail_face = *tube
        .start_cap
        .iter()
        .max_by(|a, b| cage.face_center(**a).y.total_cmp(&cage.face_center(**b).y))
        .expect("rump cap");
    let tail_bones: Vec<usize> = ["tail1", "tail2", "tail3", "tail4"]
        .iter()
        .map(|n| r.index(n))
        .collect();
    let tail = Chain::new(r, &tail_bones, Vec3::new(0.0, 0.56, -1.22));
    extrude_limb(
        &mut cage,
        tail_face,
        &tail,
        &[
            limb(0.35, 0.065, 0.06),
            limb(1.0, 0.07, 0.06),
            limb(2.0, 0.09, 0.06),
            limb(3.0, 0.115, 0.055),
            limb(3.6, 0.11, 0.05),
            limb(3.95, 0.05, 0.025),
        ],
        Vec3::X,
        TAIL,
        TAIL,
    );
    cage
}

/// Leg phase offsets and duty factors of a gait: [front left, front right, hind left, hind right].
struct Gait {
    offsets: [f32; 4],
    duty: f32,
    /// Hip and shoulder swing half-amplitude in degrees.
    swing: f32,
    /// How far the joints fold while a leg swings forward, 1 = walk.
    fold: f32,
}

/// Hip/shoulder angle (degrees, + = forward) and fold (0..1) of a leg at its own phase: the
/// hoof travels back at constant speed while on the ground, then the leg folds and swings
/// forward.
fn leg_motion(p: f32, g: &Gait) -> (f32, f32) {
    if p < g.duty {
        let u = p / g.duty;
        (g.swing * (1.0 - 2.0 * u), 0.0)
    } else {
        let u = (p - g.duty) / (1.0 - g.duty);
        let forward = 0.5 - 0.5 * (std::f32::consts::PI * u).cos();
        (
            -g.swing + 2.0 * g.swing * forward,
            (std::f32::consts::PI * u).sin(),
        )
    }
}

fn pose_legs(pose: &mut Pose, legs: &Legs, g: &Gait, phase: f32) {
    for (i, bones) in legs.bones.iter().enumerate() {
        let p = (phase + g.offsets[i]).rem_euclid(1.0);
        let (swing, fold) = leg_motion(p, g);
        let fold = fold * g.fold;
        // Rotation about +x by a negative angle moves a hanging hoof forward (+z).
        let push_off = bump(p, g.duty * 0.92, 0.12);
        if i < 2 {
            pose.rotate(bones[0], euler(-swing, 0.0, 0.0));
            pose.rotate(bones[1], euler(-20.0 * fold, 0.0, 0.0));
            pose.rotate(bones[2], euler(55.0 * fold, 0.0, 0.0));
            pose.rotate(bones[3], euler(30.0 * fold - 20.0 * push_off, 0.0, 0.0));
        } else {
            pose.rotate(bones[0], euler(-swing, 0.0, 0.0));
            pose.rotate(bones[1], euler(15.0 * fold, 0.0, 0.0));
            pose.rotate(bones[2], euler(-35.0 * fold, 0.0, 0.0));
            pose.rotate(bones[3], euler(35.0 * fold - 20.0 * push_off, 0.0, 0.0));
        }
    }
}

fn clips(r: &Rig, legs: &Legs) -> Vec<crate::model::Clip> {
    let b = |n: &str| r.index(n);
    let pelvis = b("pelvis");
    let walk = Gait {
        offsets: [0.25, 0.75, 0.0, 0.5],
        duty: 0.62,
        swing: 21.0,
        fold: 1.0,
    };
    let walk_clip = bake_clip("walk", 1.2, 1.7, r, pelvis, |ph| {
        let mut p = Pose::rest(r.len());
        pose_legs(&mut p, legs, &walk, ph);
        p.root_offset = Vec3::new(0.0, -0.015 * wave(ph, 2.0, 0.25), 0.0);
        p.rotate(
            pelvis,
            euler(0.0, 2.0 * wave(ph, 1.0, 0.0), 2.0 * wave(ph, 1.0, 0.25)),
        );
        p.rotate(b("chest"), euler(0.0, -2.0 * wave(ph, 1.0, 0.0), 0.0));
        p.rotate(b("neck1"), euler(4.0 * wave(ph, 2.0, 0.1), 0.0, 0.0));
        p.rotate(b("neck2"), euler(3.0 * wave(ph, 2.0, 0.2), 0.0, 0.0));
        p.rotate(b("head"), euler(-4.0 * wave(ph, 2.0, 0.3), 0.0, 0.0));
        for (k, t) in ["tail1", "tail2", "tail3", "tail4"].iter().enumerate() {
            p.rotate(b(t), euler(0.0, 6.0 * wave(ph, 1.0, -0.1 * k as f32), 0.0));
        }
        p
    });
    let gallop = Gait {
        offsets: [0.62, 0.52, 0.0, 0.9],
        duty: 0.34,
        swing: 36.0,
        fold: 1.5,
    };
    let gallop_clip = bake_clip("gallop", 0.55, 7.0, r, pelvis, |ph| {
        let mut p = Pose::rest(r.len());
        pose_legs(&mut p, legs, &gallop, ph);
        // The back flexes and extends once a stride; the body rises in the suspension.
        let flex = wave(ph, 1.0, 0.1);
        p.root_offset = Vec3::new(0.0, 0.06 * wave(ph, 1.0, 0.35), 0.0);
        p.rotate(pelvis, euler(5.0 * flex, 0.0, 0.0));
        p.rotate(b("spine1"), euler(-3.0 * flex, 0.0, 0.0));
        p.rotate(b("spine2"), euler(-3.0 * flex, 0.0, 0.0));
        p.rotate(b("chest"), euler(-2.0 * flex, 0.0, 0.0));
        p.rotate(
            b("neck1"),
            euler(10.0 * wave(ph, 1.0, 0.45) - 8.0, 0.0, 0.0),
        );
        p.rotate(b("neck2"), euler(6.0 * wave(ph, 1.0, 0.55), 0.0, 0.0));
        p.rotate(b("head"), euler(-8.0 * wave(ph, 1.0, 0.6) + 10.0, 0.0, 0.0));
        // The tail streams out behind.
        // Positive rotation about x swings the hanging tail backwards (−z).
        p.rotate(b("tail1"), euler(35.0 + 5.0 * wave(ph, 1.0, 0.0), 0.0, 0.0));
        for (k, t) in ["tail2", "tail3", "tail4"].iter().enumerate() {
            p.rotate(
                b(t),
                euler(15.0 + 8.0 * wave(ph, 1.0, -0.15 * (k + 1) as f32), 0.0, 0.0),
            );
        }
        p
    });
    vec![walk_clip, gallop_clip]
}

/// Bay coat: red-brown body, black mane, tail and lower legs, a white blaze, dark eyes.
fn coat(eyes: [Vec3; 2], nostrils: [Vec3; 2]) -> impl Fn(u32, Vec3, Vec3) -> Vec3 {
    move |part, p, n| {
        let bay = Vec3::new(0.52, 0.29, 0.15);
        let black = Vec3::new(0.09, 0.07, 0.06);
        let dapple = 0.82 + 0.32 * fbm(p * 7.0);
        let mut c = bay * dapple;
        // Lighter belly and inner legs, darker top line.
        c = c.lerp(Vec3::new(0.66, 0.47, 0.32), smooth(-0.2, -0.85, n.y) * 0.6);
        c *= 0.94 + 0.08 * smooth(0.2, 0.9, n.y);
        match part {
            LEG | HOOF => {
                c = c.lerp(
                    black * (0.9 + 0.3 * noise(p * 30.0)),
                    smooth(0.62, 0.44, p.y),
                );
                if p.y < 0.075 || part == HOOF {
                    c = Vec3::new(0.20, 0.18, 0.16) * (0.9 + 0.2 * noise(p * 60.0));
                }
            }
            TAIL => c = black * (0.8 + 0.5 * noise(Vec3::new(p.x * 90.0, p.y * 6.0, p.z * 90.0))),
            NECK | HEAD => {
                // Mane along the crest: the upper back of the neck.
                let crest = n.dot(Vec3::new(0.0, 0.55, -0.83));
                let mane = smooth(0.25, 0.55, crest) * smooth(0.08, 0.03, p.x.abs());
                let streaks = 0.7 + 0.6 * noise(Vec3::new(p.x * 80.0, p.y * 5.0, p.z * 80.0));
                if part == NECK || p.z < 1.2 {
                    c = c.lerp(black * streaks, mane);
                }
                if part == HEAD {
                    // White blaze down the face.
                    let width = 0.012 + 0.008 * smooth(1.6, 1.3, p.z);
                    let blaze = smooth(width + 0.006, width, p.x.abs())
                        * smooth(0.2, 0.5, n.dot(Vec3::new(0.0, 0.6, 0.8)))
                        * smooth(1.22, 1.28, p.z)
                        * smooth(1.62, 1.56, p.z);
                    c = c.lerp(Vec3::new(0.82, 0.79, 0.74), blaze);
                    // Darker muzzle.
                    c = c.lerp(Vec3::new(0.22, 0.17, 0.14), smooth(1.52, 1.62, p.z) * 0.85);
                }
            }
            EAR => c = c.lerp(black, 0.35 + 0.4 * smooth(0.3, 0.8, n.z)),
            NOSE => c = Vec3::new(0.2, 0.16, 0.14),
            _ => {}
        }
        for e in eyes {
            let d = p.distance(e);
            if d < 0.03 {
                c = Vec3::new(0.06, 0.04, 0.03);
                if d < 0.009 && p.y > e.y {
                    c = Vec3::new(0.5, 0.45, 0.4);
                }
            } else if d < 0.036 {
                c *= 0.55;
            }
        }
        for nostril in nostrils {
            if p.distance(nostril) < 0.018 {
                c = Vec3::new(0.05, 0.04, 0.04);
            }
        }
        c
    }
}

pub fn horse() -> Model {
    let (r, legs) = rig();
    assemble(
        "horse",
        "bay coat",
        &r,
        cage(&r, &legs),
        clips(&r, &legs),
        |surface| {
            let eye = |x: f32| nearest_surface_point(surface, Vec3::new(x * 0.14, 1.77, 1.27));
            let nostril = |x: f32| nearest_surface_point(surface, Vec3::new(x * 0.05, 1.42, 1.72));
            Box::new(coat([eye(1.0), eye(-1.0)], [nostril(1.0), nostril(-1.0)]))
        },
    )
}
