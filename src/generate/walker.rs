//! "walker": a biped in shirt and trousers, 25 bones, arms with hands and thumbs, legs with
//! feet and toes, a head with ears and a nose. Clips: `walk` and `wave` (waving on the spot).
//!
//! Metres, facing +z, standing on y = 0, left side at +x, arms in an A-pose 40° below the
//! horizontal (a rest pose that skins better than a T-pose when the arms hang).

use super::build::{
    OCTAGON, Section, assemble, assemble_subdivided, body_rings, extrude_limb, extrude_rigid, limb,
    nearest_surface_point, section,
};
use super::cage::{Cage, Cap, Tube};
use super::finish::{fbm, noise, smooth};
use super::rig::{Chain, Pose, Rig, bake_clip, bump, euler, rigid, wave};
use crate::model::Model;
use glam::{Vec2, Vec3};

// Parts, for the painter.
const TORSO: u32 = 0;
const HEAD: u32 = 1;
const ARM: u32 = 2;
const THUMB: u32 = 3;
const LEG: u32 = 4;
const SOLE: u32 = 5;
const SKIN: u32 = 6;

/// Arms hang this many degrees below the horizontal in the rest pose.
const A_POSE: f32 = 40.0;

struct Limbs {
    /// Per side [left, right]: upper arm, forearm, hand, fingers; and the fingertip.
    arms: [[usize; 4]; 2],
    arm_ends: [Vec3; 2],
    thumbs: [usize; 2],
    thumb_ends: [Vec3; 2],
    /// Per side: thigh, shin, foot, toe; and the toe tip.
    legs: [[usize; 4]; 2],
    leg_ends: [Vec3; 2],
}

fn rig() -> (Rig, Limbs) {
    let mut r = Rig::default();
    let hips = r.bone("hips", None, Vec3::new(0.0, 1.0, 0.0));
    let spine = r.bone("spine", Some(hips), Vec3::new(0.0, 1.13, -0.005));
    let chest = r.bone("chest", Some(spine), Vec3::new(0.0, 1.32, -0.01));
    let neck = r.bone("neck", Some(chest), Vec3::new(0.0, 1.52, 0.0));
    r.bone("head", Some(neck), Vec3::new(0.0, 1.62, 0.01));
    let (sin, cos) = A_POSE.to_radians().sin_cos();
    let mut limbs = Limbs {
        arms: [[0; 4]; 2],
        arm_ends: [Vec3::ZERO; 2],
        thumbs: [0; 2],
        thumb_ends: [Vec3::ZERO; 2],
        legs: [[0; 4]; 2],
        leg_ends: [Vec3::ZERO; 2],
    };
    for (i, (side, s)) in [("l", 1.0f32), ("r", -1.0)].into_iter().enumerate() {
        let d = Vec3::new(s * cos, -sin, 0.0);
        let clavicle = r.bone(
            &format!("clavicle_{side}"),
            Some(chest),
            Vec3::new(s * 0.03, 1.47, 0.0),
        );
        let shoulder = Vec3::new(s * 0.18, 1.46, -0.01);
        let upper = r.bone(&format!("upper_arm_{side}"), Some(clavicle), shoulder);
        let elbow = shoulder + d * 0.28;
        let fore = r.bone(&format!("forearm_{side}"), Some(upper), elbow);
        let wrist = elbow + d * 0.255;
        let hand = r.bone(&format!("hand_{side}"), Some(fore), wrist);
        let knuckles = wrist + d * 0.085;
        let fingers = r.bone(&format!("fingers_{side}"), Some(hand), knuckles);
        limbs.arms[i] = [upper, fore, hand, fingers];
        limbs.arm_ends[i] = knuckles + d * 0.085;
        let thumb_root = wrist + d * 0.03 + Vec3::new(0.0, 0.0, 0.03);
        limbs.thumbs[i] = r.bone(&format!("thumb_{side}"), Some(hand), thumb_root);
        limbs.thumb_ends[i] = thumb_root + Vec3::new(s * 0.01, -0.04, 0.03);

        let thigh = r.bone(
            &format!("thigh_{side}"),
            Some(hips),
            Vec3::new(s * 0.095, 0.94, 0.0),
        );
        let shin = r.bone(
            &format!("shin_{side}"),
            Some(thigh),
            Vec3::new(s * 0.10, 0.52, 0.01),
        );
        let foot = r.bone(
            &format!("foot_{side}"),
            Some(shin),
            Vec3::new(s * 0.10, 0.09, -0.02),
        );
        let toe = r.bone(
            &format!("toe_{side}"),
            Some(foot),
            Vec3::new(s * 0.10, 0.025, 0.11),
        );
        limbs.legs[i] = [thigh, shin, foot, toe];
        limbs.leg_ends[i] = Vec3::new(s * 0.10, 0.02, 0.19);
    }
    (r, limbs)
}

/// Torso from the crotch up, neck and head.
const SECTIONS: [Section; 17] = [
    section(0.0, 0.89, 0.0, 0.13, 0.085),
    section(0.0, 0.97, 0.0, 0.165, 0.10),
    section(0.0, 1.06, -0.005, 0.17, 0.105),
    section(0.0, 1.15, -0.005, 0.148, 0.095),
    section(0.0, 1.24, 0.0, 0.158, 0.10),
    section(0.0, 1.33, 0.005, 0.178, 0.113),
    section(0.0, 1.41, 0.0, 0.19, 0.11),
    section(0.0, 1.485, -0.01, 0.19, 0.09),
    section(0.0, 1.525, -0.01, 0.12, 0.07),
    // Neck.
    section(0.0, 1.565, 0.0, 0.055, 0.055),
    section(0.0, 1.61, 0.005, 0.057, 0.06),
    // Head: jaw, cheeks, temples, crown.
    section(0.0, 1.655, 0.015, 0.075, 0.085),
    section(0.0, 1.705, 0.015, 0.088, 0.10),
    section(0.0, 1.765, 0.01, 0.095, 0.105),
    section(0.0, 1.825, 0.005, 0.088, 0.097),
    section(0.0, 1.87, 0.0, 0.06, 0.065),
    section(0.0, 1.895, 0.0, 0.03, 0.033),
];
const HEAD_START: usize = 8;
const ARM_SEGMENT: usize = 6;
const FACE_SEGMENT: usize = 12;

fn cage(r: &Rig, l: &Limbs) -> Cage {
    let mut cage = Cage::default();
    let tube = body(&mut cage, r);
    shoulders(&mut cage, r, &tube);
    for (i, s) in [1.0f32, -1.0].into_iter().enumerate() {
        arm(&mut cage, r, l, &tube, i, s);
        leg(&mut cage, r, l, &tube, i, s);
        ear(&mut cage, r, &tube, s);
    }
    nose(&mut cage, r, &tube);
    cage
}

/// The body tube (torso, neck and head) along the spine, which the limbs, ears and nose are
/// extruded from.
fn body(cage: &mut Cage, r: &Rig) -> Tube {
    let spine_bones: Vec<usize> = ["hips", "spine", "chest", "neck", "head"]
        .iter()
        .map(|n| r.index(n))
        .collect();
    let spine = Chain::new(r, &spine_bones, Vec3::new(0.0, 1.9, 0.0));
    // The crotch cap splits into left, middle and right quads: the legs hang from the outer two.
    cage.tube(
        &body_rings(&SECTIONS, &OCTAGON, Vec3::X, &spine),
        &[(0, TORSO), (HEAD_START, HEAD)],
        Cap {
            offset: 2,
            part: TORSO,
        },
        Cap {
            offset: 0,
            part: HEAD,
        },
    )
}

/// The shoulders' weights: the outer vertices of the rings round the shoulders go partly to
/// the clavicle of their side, so that raising an arm lifts the shoulder.
fn shoulders(cage: &mut Cage, r: &Rig, tube: &Tube) {
    // Shoulders: the torso's upper rings share their outer vertices between the chest and the
    // clavicle of that side, so raising an arm lifts the shoulder with it.
    let chest = r.index("chest") as u32;
    let clavicles = [r.index("clavicle_l") as u32, r.index("clavicle_r") as u32];
    let shoulder_ring_vertices: Vec<u32> = tube.rings[ARM_SEGMENT..=ARM_SEGMENT + 2].concat();
    cage.reweight(&shoulder_ring_vertices, |p, w| {
        let k = 0.5 * smooth(0.07, 0.17, p.x.abs());
        if k <= 0.0 || !w.iter().any(|e| e.0 == chest) {
            return None;
        }
        let clavicle = clavicles[if p.x > 0.0 { 0 } else { 1 }];
        let mut out: Vec<(u32, f32)> = w.iter().map(|&(b, x)| (b, x * (1.0 - k))).collect();
        out.push((clavicle, k));
        out.sort_by_key(|e| e.0);
        Some(out)
    });
}

/// Side `i`'s arm (`s` its sign), extruded from the chest along the arm's bones to a hand,
/// and its thumb extruded from the palm.
fn arm(cage: &mut Cage, r: &Rig, l: &Limbs, tube: &Tube, i: usize, s: f32) {
    // Arm, from the side of the chest below the shoulder.
    let face = cage.face_towards(&tube.sides[ARM_SEGMENT], Vec3::new(s, 0.0, 0.0));
    let arm = Chain::new(r, &l.arms[i], l.arm_ends[i]);
    let ext = extrude_limb(
        cage,
        face,
        &arm,
        &[
            limb(0.25, 0.062, 0.06),
            limb(0.55, 0.056, 0.053),
            limb(0.85, 0.048, 0.046),
            limb(1.0, 0.045, 0.043),
            limb(1.3, 0.047, 0.041),
            limb(1.75, 0.037, 0.031),
            limb(1.97, 0.033, 0.025),
            limb(2.3, 0.052, 0.02),
            limb(2.9, 0.052, 0.019),
            limb(3.4, 0.047, 0.016),
            limb(3.95, 0.033, 0.012),
        ],
        Vec3::Z,
        ARM,
        SKIN,
    );
    // Thumb, from the front of the palm.
    let palm = cage.face_towards(&ext.sides[7], Vec3::Z);
    let thumb = Chain::new(r, &[l.thumbs[i]], l.thumb_ends[i]);
    extrude_limb(
        cage,
        palm,
        &thumb,
        &[
            limb(0.35, 0.017, 0.015),
            limb(0.7, 0.014, 0.013),
            limb(0.97, 0.009, 0.009),
        ],
        Vec3::X,
        THUMB,
        SKIN,
    );
}

/// Side `i`'s leg (`s` its sign), extruded from the crotch cap's outer quad on that side along
/// the leg's bones to a foot with a sole.
fn leg(cage: &mut Cage, r: &Rig, l: &Limbs, tube: &Tube, i: usize, s: f32) {
    // Leg, from the crotch.
    let face = *tube
        .start_cap
        .iter()
        .max_by(|a, b| (s * cage.face_center(**a).x).total_cmp(&(s * cage.face_center(**b).x)))
        .expect("crotch cap");
    let leg = Chain::new(r, &l.legs[i], l.leg_ends[i]);
    extrude_limb(
        cage,
        face,
        &leg,
        &[
            limb(0.22, 0.095, 0.1),
            limb(0.5, 0.082, 0.088),
            limb(0.85, 0.064, 0.068),
            limb(1.0, 0.06, 0.066),
            limb(1.2, 0.062, 0.068),
            limb(1.6, 0.05, 0.053),
            limb(1.9, 0.043, 0.047),
            limb(2.1, 0.05, 0.055),
            limb(2.5, 0.052, 0.042),
            limb(2.95, 0.05, 0.032),
            limb(3.5, 0.045, 0.027),
            limb(3.95, 0.036, 0.022),
        ],
        Vec3::X,
        LEG,
        SOLE,
    );
}

/// The ear on side `s` of the head: a short rigid extrusion on the head bone.
fn ear(cage: &mut Cage, r: &Rig, tube: &Tube, s: f32) {
    // An ear on either side of the head.
    let head = rigid(r.index("head"));
    let side_face = cage.face_towards(&tube.sides[FACE_SEGMENT], Vec3::new(s, 0.0, -0.2));
    let c = cage.face_center(side_face);
    extrude_rigid(
        cage,
        side_face,
        &[
            (
                c + Vec3::new(s * 0.012, 0.0, -0.004),
                Vec2::new(0.024, 0.03),
            ),
            (
                c + Vec3::new(s * 0.02, 0.002, -0.008),
                Vec2::new(0.016, 0.022),
            ),
        ],
        &head,
        Vec3::Z,
        HEAD,
        HEAD,
    );
}

/// The nose: a short rigid extrusion on the head bone from the face's front.
fn nose(cage: &mut Cage, r: &Rig, tube: &Tube) {
    // Nose.
    let head = rigid(r.index("head"));
    let front = cage.face_towards(&tube.sides[FACE_SEGMENT], Vec3::Z);
    let c = cage.face_center(front);
    extrude_rigid(
        cage,
        front,
        &[
            (c + Vec3::new(0.0, -0.012, 0.012), Vec2::new(0.022, 0.024)),
            (c + Vec3::new(0.0, -0.022, 0.024), Vec2::new(0.014, 0.013)),
        ],
        &head,
        Vec3::X,
        HEAD,
        HEAD,
    );
}

fn clips(r: &Rig, l: &Limbs) -> Vec<crate::model::Clip> {
    let b = |n: &str| r.index(n);
    let hips = b("hips");
    let sides = [1.0f32, -1.0];
    let walk = bake_clip("walk", 1.1, 1.35, r, hips, |ph| {
        let mut p = Pose::rest(r.len());
        let mut hip_angle = [0.0f32; 2];
        for (i, hip_out) in hip_angle.iter_mut().enumerate() {
            // Leg phase 0 is heel strike; stance to 0.6, swing after.
            let q = (ph + 0.5 * i as f32).rem_euclid(1.0);
            let hip = 21.0 * (std::f32::consts::TAU * q).cos() + 3.0;
            *hip_out = hip;
            let knee = 12.0 * bump(q, 0.1, 0.12) + 58.0 * bump(q, 0.72, 0.2) + 4.0;
            let ankle =
                20.0 * bump(q, 0.57, 0.1) - 10.0 * bump(q, 0.8, 0.15) - 5.0 * bump(q, 0.0, 0.08);
            let [thigh, shin, foot, toe] = l.legs[i];
            p.rotate(thigh, euler(-hip, 0.0, 0.0));
            p.rotate(shin, euler(knee, 0.0, 0.0));
            p.rotate(foot, euler(ankle, 0.0, 0.0));
            p.rotate(toe, euler(-28.0 * bump(q, 0.57, 0.1), 0.0, 0.0));
        }
        for (i, s) in sides.into_iter().enumerate() {
            // Each arm swings with the opposite leg.
            let swing = 0.8 * hip_angle[1 - i] - 2.0;
            let [upper, fore, hand, _] = l.arms[i];
            p.rotate(upper, euler(0.0, 0.0, -s * 37.0));
            p.rotate(upper, euler(-swing, 0.0, 0.0));
            p.rotate(
                fore,
                euler(-(14.0 + 10.0 * (swing / 20.0).max(0.0)), 0.0, 0.0),
            );
            p.rotate(hand, euler(0.0, 0.0, s * 6.0));
        }
        let c = (std::f32::consts::TAU * ph).cos();
        p.root_offset = Vec3::new(
            0.015 * wave(ph, 1.0, 0.0),
            -0.018 * (2.0 * std::f32::consts::TAU * ph).cos(),
            0.0,
        );
        p.rotate(hips, euler(0.0, -5.0 * c, 2.5 * wave(ph, 1.0, 0.0)));
        p.rotate(b("spine"), euler(2.0, 2.0 * c, -1.5 * wave(ph, 1.0, 0.0)));
        p.rotate(b("chest"), euler(0.0, 4.0 * c, 0.0));
        p.rotate(b("neck"), euler(-1.0, -c, 0.0));
        p
    });
    let wave_clip = bake_clip("wave", 2.4, 0.0, r, hips, |ph| {
        let mut p = Pose::rest(r.len());
        // The right arm waves, the left hangs.
        let (s, i) = (-1.0f32, 1usize);
        let [upper, fore, hand, fingers] = l.arms[i];
        p.rotate(b("clavicle_r"), euler(0.0, 0.0, s * 12.0));
        p.rotate(upper, euler(0.0, 0.0, s * 52.0));
        p.rotate(upper, euler(-18.0, 0.0, 0.0));
        p.rotate(
            fore,
            euler(0.0, 0.0, s * (78.0 + 24.0 * wave(ph, 4.0, 0.0))),
        );
        p.rotate(hand, euler(0.0, 0.0, s * 10.0 * wave(ph, 4.0, 0.12)));
        p.rotate(fingers, euler(0.0, 0.0, s * 6.0 * wave(ph, 4.0, 0.2)));
        let [upper, fore, _, _] = l.arms[0];
        p.rotate(upper, euler(0.0, 0.0, -37.0 + 2.0 * wave(ph, 1.0, 0.0)));
        p.rotate(upper, euler(-3.0 * wave(ph, 1.0, 0.3), 0.0, 0.0));
        p.rotate(fore, euler(-12.0, 0.0, 0.0));
        // Weight shifts from foot to foot; head tilts towards the wave.
        let shift = wave(ph, 1.0, 0.0);
        p.root_offset = Vec3::new(0.02 * shift, -0.01 - 0.004 * wave(ph, 2.0, 0.0), 0.0);
        p.rotate(hips, euler(0.0, 3.0 * shift, -2.0 * shift));
        p.rotate(b("spine"), euler(0.0, 0.0, 1.5 * shift));
        p.rotate(b("chest"), euler(0.0, 0.0, 1.0 * shift));
        p.rotate(
            b("head"),
            euler(3.0 * wave(ph, 2.0, 0.1), -4.0, -5.0 + 2.0 * shift),
        );
        for (k, s) in sides.into_iter().enumerate() {
            let [thigh, shin, foot, _] = l.legs[k];
            let bend = 4.0 + 4.0 * (s * shift).max(0.0);
            p.rotate(thigh, euler(-bend, 0.0, s * 1.5 * shift));
            p.rotate(shin, euler(2.0 * bend, 0.0, 0.0));
            p.rotate(foot, euler(-bend, 0.0, 0.0));
        }
        p
    });
    vec![walk, wave_clip]
}

/// Blue shirt with short sleeves, charcoal trousers, brown shoes and belt, dark hair.
fn clothes(r: &Rig, l: &Limbs, eyes: [Vec3; 2]) -> impl Fn(u32, Vec3, Vec3) -> Vec3 + use<> {
    let shoulders = [r.heads[l.arms[0][0]], r.heads[l.arms[1][0]]];
    let wrists = [r.heads[l.arms[0][2]], r.heads[l.arms[1][2]]];
    move |part, p, n| {
        let skin = Vec3::new(0.86, 0.64, 0.50) * (0.95 + 0.08 * noise(p * 40.0));
        let shirt = Vec3::new(0.20, 0.40, 0.66) * (0.88 + 0.16 * fbm(p * 60.0));
        let trousers = Vec3::new(0.22, 0.22, 0.25) * (0.9 + 0.14 * fbm(p * 50.0));
        let shoe = Vec3::new(0.16, 0.10, 0.07) * (0.9 + 0.2 * noise(p * 80.0));
        let hair = Vec3::new(0.20, 0.12, 0.07)
            * (0.8 + 0.4 * noise(Vec3::new(p.x * 120.0, p.y * 30.0, p.z * 120.0)));
        match part {
            TORSO => {
                if p.y > 1.03 {
                    shirt
                } else if p.y > 0.985 {
                    Vec3::new(0.18, 0.11, 0.07)
                } else {
                    trousers
                }
            }
            ARM | SKIN | THUMB => {
                let side = if p.x > 0.0 { 0 } else { 1 };
                let along = (p - shoulders[side]).dot((wrists[side] - shoulders[side]).normalize());
                if part == ARM && along < 0.2 {
                    shirt
                } else {
                    skin
                }
            }
            LEG | SOLE => {
                if p.y < 0.11 || part == SOLE {
                    let sole = smooth(0.03, 0.015, p.y);
                    shoe.lerp(Vec3::new(0.08, 0.07, 0.06), sole)
                } else {
                    trousers
                }
            }
            HEAD => {
                let mut c = if p.y < 1.6 { skin } else { skin * 1.02 };
                // Hair on the crown and the back of the head.
                let front = n.z;
                let hairline = 1.79 - 0.09 * smooth(0.2, -0.6, front);
                if p.y > hairline {
                    c = hair;
                }
                for e in eyes {
                    let d = p.distance(e);
                    if d < 0.011 {
                        c = Vec3::new(0.08, 0.06, 0.05);
                    } else if d < 0.016 {
                        c = Vec3::new(0.92, 0.9, 0.86);
                    }
                    // Eyebrow.
                    let brow = Vec2::new(p.x - e.x, p.y - e.y - 0.022);
                    if brow.y.abs() < 0.004 && brow.x.abs() < 0.016 && front > 0.3 {
                        c = hair;
                    }
                }
                // Mouth.
                if front > 0.5 && (p.y - 1.686).abs() < 0.004 && p.x.abs() < 0.02 {
                    c = Vec3::new(0.55, 0.27, 0.25);
                }
                c
            }
            _ => skin,
        }
    }
}

fn eyes(surface: &[Vec3]) -> [Vec3; 2] {
    let eye = |x: f32| nearest_surface_point(surface, Vec3::new(x * 0.034, 1.752, 0.12));
    [eye(1.0), eye(-1.0)]
}

pub fn walker() -> Model {
    let (r, l) = rig();
    assemble(
        "walker",
        "clothes",
        &r,
        cage(&r, &l),
        clips(&r, &l),
        |surface| Box::new(clothes(&r, &l, eyes(surface))),
    )
}

/// "patchwork": a test model with the texture layout of automatically unwrapped game assets,
/// which the demo creatures lack. The walker, subdivided once (2,928 triangles), its charts cut
/// into patches of 12 cm (5 cm on the head), so its texture lies in a couple of hundred
/// charts whose outlines split every position on them and whose corners join three or four.
pub fn patchwork() -> Model {
    let (r, l) = rig();
    let mut cage = cage(&r, &l).subdivide();
    cage.split_charts(|part| if part == HEAD { 0.05 } else { 0.12 });
    assemble_subdivided("patchwork", "clothes", &r, cage, clips(&r, &l), |surface| {
        Box::new(clothes(&r, &l, eyes(surface)))
    })
}

/// "lowpoly": a test model with the properties of low-poly game characters: the walker's
/// control cage itself (732 triangles), every quad flat-shaded (a hard edge all round it),
/// no texture coordinates, coloured by six plain materials (tunic, sleeves, trousers, boots,
/// gloves and skin) where its parts meet.
pub fn lowpoly() -> Model {
    use super::facets::FacetBuilder;
    use crate::model::Material;
    let (r, l) = rig();
    let cage = cage(&r, &l);
    let mut b = FacetBuilder::default();
    let ids: Vec<u32> = cage
        .positions
        .iter()
        .zip(&cage.weights)
        .map(|(p, w)| b.point(*p, w.clone()))
        .collect();
    let mut part_of_group = Vec::new();
    for (g, f) in cage.live_faces().enumerate() {
        b.quad(f.v.map(|v| ids[v as usize]), g as u32, [Vec2::ZERO; 4]);
        part_of_group.push(cage.chart_parts[f.chart as usize]);
    }
    let material = |part: u32| match part {
        TORSO => 0,
        ARM => 1,
        LEG => 2,
        SOLE => 3,
        THUMB => 4,
        _ => 5,
    };
    let mesh = b.build_coloured(0.0, |g, _| material(part_of_group[g as usize]));
    Model {
        name: "lowpoly".into(),
        mesh,
        skeleton: r.skeleton(),
        clips: clips(&r, &l),
        materials: vec![
            Material::opaque("tunic", [0.16, 0.3, 0.12, 1.0], None),
            Material::opaque("sleeves", [0.1, 0.2, 0.08, 1.0], None),
            Material::opaque("trousers", [0.42, 0.36, 0.22, 1.0], None),
            Material::opaque("boots", [0.05, 0.04, 0.03, 1.0], None),
            Material::opaque("gloves", [0.3, 0.17, 0.08, 1.0], None),
            Material::opaque("skin", [0.8, 0.55, 0.42, 1.0], None),
        ],
    }
}
