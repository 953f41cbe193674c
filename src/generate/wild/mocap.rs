//! "mocap": a character laid out as an auto-rigging service delivers one. The walker's body,
//! bound in a T-pose with its arms out level, on a skeleton of 65 joints named as Mixamo names them (`mixamorig:Hips`, …, four joints to a
//! finger, `HeadTop_End`, `LeftToe_End`), oriented along their bones, in centimetres and Z up
//! under an `Armature` node that turns and scales the whole to metres and Y up; up to four
//! influences a vertex, fingers blended across their joints; and for its only clip a two-key
//! `T-Pose` that does not move. Its walk comes as a second file, `mocap-walk`, as the service
//! sends animations: the same skeleton and a clip, no mesh, bound by joint name
//! (`--clips`).

use super::file::{DocMesh, DocPrimitive, DocSkin, Document};
use crate::model::{
    Channel, ChannelTarget, Clip, Influence, Interpolation, Model, SkinnedMesh, Trs,
};
use glam::{Affine3A, Mat4, Quat, Vec3, Vec4};

/// The most influences a vertex keeps, as the service writes them.
const MAX_INFLUENCES: usize = 4;

/// One joint of the rig: its name, parent, head (metres, Y up, the walker's space), and the
/// walker bone whose motion and weights it takes.
struct Joint {
    name: String,
    parent: Option<usize>,
    head: Vec3,
    /// The walker bone it follows in a clip.
    follows: Option<usize>,
}

/// The armature node: centimetres and Z up to metres and Y up.
fn armature() -> Trs {
    Trs {
        translation: Vec3::ZERO,
        rotation: Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
        scale: Vec3::splat(0.01),
    }
}

/// The walker, its arms raised from its A-pose to a T-pose (as a rigging service binds), with
/// its bones by name.
struct Walker {
    model: Model,
    /// Every bone's matrix (bone to scene) in the T-pose.
    tpose: Vec<Affine3A>,
}

impl Walker {
    fn new() -> Walker {
        let model = crate::generate::walker::walker();
        let skel = &model.skeleton;
        let mut local = crate::anim::local_pose(skel, None, 0.0);
        for (name, turn) in [("upper_arm_l", 1.0f32), ("upper_arm_r", -1.0)] {
            let b = skel
                .nodes
                .iter()
                .position(|n| n.name == name)
                .expect("the walker has arms");
            local[b].rotation = Quat::from_rotation_z(turn * 40f32.to_radians());
        }
        let tpose = crate::anim::global_transforms(skel, &local);
        Walker { model, tpose }
    }

    /// Vertex `v`'s position and normal in the T-pose.
    fn vertex(&self, v: usize) -> (Vec3, Vec3) {
        let m = &self.model.mesh;
        let (mut p, mut n) = (Vec3::ZERO, Vec3::ZERO);
        for inf in m.influences_of(v) {
            let b = inf.bone as usize;
            let skin = self.tpose[b] * Affine3A::from_mat4(self.model.skeleton.inverse_bind[b]);
            p += inf.weight * skin.transform_point3(m.positions[v]);
            n += inf.weight * skin.transform_vector3(m.normals[v]);
        }
        (p, n.normalize_or(Vec3::Y))
    }

    fn bone(&self, name: &str) -> usize {
        self.model
            .skeleton
            .nodes
            .iter()
            .position(|n| n.name == name)
            .unwrap_or_else(|| panic!("the walker has a bone {name}"))
    }

    /// Bone `name`'s head in the walker's own A-pose.
    fn rest_head(&self, name: &str) -> Vec3 {
        -self.model.skeleton.inverse_bind[self.bone(name)]
            .w_axis
            .truncate()
    }

    /// A point carried rigidly by bone `name` from the A-pose to the T-pose.
    fn carried(&self, name: &str, p: Vec3) -> Vec3 {
        let b = self.bone(name);
        (self.tpose[b] * Affine3A::from_mat4(self.model.skeleton.inverse_bind[b]))
            .transform_point3(p)
    }

    /// Bone `name`'s head in the T-pose.
    fn head(&self, name: &str) -> Vec3 {
        Vec3::from(self.tpose[self.bone(name)].translation)
    }
}

/// Adds joint `mixamorig:{name}` to `j` and returns its index.
fn add_joint(
    j: &mut Vec<Joint>,
    name: &str,
    parent: Option<usize>,
    head: Vec3,
    follows: Option<usize>,
) -> usize {
    j.push(Joint {
        name: format!("mixamorig:{name}"),
        parent,
        head,
        follows,
    });
    j.len() - 1
}

/// The 65 joints, parents first.
fn joints(w: &Walker) -> Vec<Joint> {
    let mut j: Vec<Joint> = Vec::new();
    let (hips, spine2) = spine_joints(&mut j, w);
    for (side, s, x) in [("Left", "l", 1.0f32), ("Right", "r", -1.0)] {
        arm_joints(&mut j, w, (side, s, x), spine2);
        leg_joints(&mut j, w, (side, s, x), hips);
    }
    j
}

/// The trunk's joints, `Hips` to `HeadTop_End`, returning `Hips` and `Spine2` (what the legs
/// and the shoulders hang from). The walker's one chest bone becomes two spine joints, as the
/// service's rig has more spine than the walker.
fn spine_joints(j: &mut Vec<Joint>, w: &Walker) -> (usize, usize) {
    let hips = add_joint(j, "Hips", None, w.head("hips"), Some(w.bone("hips")));
    let spine = add_joint(
        j,
        "Spine",
        Some(hips),
        w.head("spine"),
        Some(w.bone("spine")),
    );
    let chest = w.bone("chest");
    let spine1 = add_joint(j, "Spine1", Some(spine), w.head("chest"), Some(chest));
    let spine2 = add_joint(
        j,
        "Spine2",
        Some(spine1),
        w.head("chest").lerp(w.head("neck"), 0.5),
        Some(chest),
    );
    let neck = add_joint(
        j,
        "Neck",
        Some(spine2),
        w.head("neck"),
        Some(w.bone("neck")),
    );
    let head = add_joint(j, "Head", Some(neck), w.head("head"), Some(w.bone("head")));
    add_joint(
        j,
        "HeadTop_End",
        Some(head),
        w.head("head") + Vec3::new(0.0, 0.19, 0.0),
        Some(w.bone("head")),
    );
    (hips, spine2)
}

/// One side's arm (`side` as Mixamo spells it, `s` as the walker does, `x` the side's sign):
/// shoulder, arm, forearm and hand under `spine2`, then the hand's fingers and thumb.
fn arm_joints(j: &mut Vec<Joint>, w: &Walker, (side, s, x): (&str, &str, f32), spine2: usize) {
    let b = |n: &str| format!("{n}_{s}");
    let shoulder = add_joint(
        j,
        &format!("{side}Shoulder"),
        Some(spine2),
        w.head(&b("clavicle")),
        Some(w.bone(&b("clavicle"))),
    );
    let arm = add_joint(
        j,
        &format!("{side}Arm"),
        Some(shoulder),
        w.head(&b("upper_arm")),
        Some(w.bone(&b("upper_arm"))),
    );
    let fore = add_joint(
        j,
        &format!("{side}ForeArm"),
        Some(arm),
        w.head(&b("forearm")),
        Some(w.bone(&b("forearm"))),
    );
    let wrist = w.head(&b("hand"));
    let hand = add_joint(
        j,
        &format!("{side}Hand"),
        Some(fore),
        wrist,
        Some(w.bone(&b("hand"))),
    );
    finger_joints(j, w, (side, s, x), hand, wrist);
}

/// One hand's digits: four joints to each finger (index to pinky), laid out from the walker's
/// knuckles, then four to the thumb, all on the walker's one fingers or thumb bone, since the
/// service's rig has joints the walker lacks.
fn finger_joints(
    j: &mut Vec<Joint>,
    w: &Walker,
    (side, s, x): (&str, &str, f32),
    hand: usize,
    wrist: Vec3,
) {
    let b = |n: &str| format!("{n}_{s}");
    let knuckles = w.head(&b("fingers"));
    let d = (knuckles - wrist) / 0.085;
    let fingers = w.bone(&b("fingers"));
    for (finger, z) in [
        ("Index", 0.022f32),
        ("Middle", 0.007),
        ("Ring", -0.008),
        ("Pinky", -0.022),
    ] {
        let base = knuckles + Vec3::new(0.0, 0.0, z);
        let mut parent = hand;
        for k in 1..=4 {
            let along = [0.0, 0.035, 0.06, 0.085][k - 1];
            parent = add_joint(
                j,
                &format!("{side}Hand{finger}{k}"),
                Some(parent),
                base + d * along,
                Some(fingers),
            );
        }
    }
    let thumb_root = w.head(&b("thumb"));
    // The walker's thumb tip (placed from its root in the A-pose), carried to the T-pose.
    let thumb_end = w.carried(
        &b("thumb"),
        w.rest_head(&b("thumb")) + Vec3::new(x * 0.01, -0.04, 0.03),
    );
    let thumb = w.bone(&b("thumb"));
    let mut parent = hand;
    for k in 1..=4 {
        parent = add_joint(
            j,
            &format!("{side}HandThumb{k}"),
            Some(parent),
            thumb_root.lerp(thumb_end, (k - 1) as f32 / 3.0),
            Some(thumb),
        );
    }
}

/// One side's leg under `hips`: up leg, leg, foot, toe base and the toe's end joint.
fn leg_joints(j: &mut Vec<Joint>, w: &Walker, (side, s, x): (&str, &str, f32), hips: usize) {
    let b = |n: &str| format!("{n}_{s}");
    let up = add_joint(
        j,
        &format!("{side}UpLeg"),
        Some(hips),
        w.head(&b("thigh")),
        Some(w.bone(&b("thigh"))),
    );
    let leg = add_joint(
        j,
        &format!("{side}Leg"),
        Some(up),
        w.head(&b("shin")),
        Some(w.bone(&b("shin"))),
    );
    let foot = add_joint(
        j,
        &format!("{side}Foot"),
        Some(leg),
        w.head(&b("foot")),
        Some(w.bone(&b("foot"))),
    );
    let toe = add_joint(
        j,
        &format!("{side}ToeBase"),
        Some(foot),
        w.head(&b("toe")),
        Some(w.bone(&b("toe"))),
    );
    add_joint(
        j,
        &format!("{side}Toe_End"),
        Some(toe),
        Vec3::new(x * 0.10, 0.02, 0.19),
        Some(w.bone(&b("toe"))),
    );
}

/// Every joint's orientation in the armature's space: its Y axis along the bone to its first
/// child (an end keeps its parent's), as rigging tools orient joints.
fn orientations(joints: &[Joint], to_armature: &Mat4) -> Vec<Quat> {
    let mut q = vec![Quat::IDENTITY; joints.len()];
    for i in 0..joints.len() {
        let child = joints.iter().position(|c| c.parent == Some(i));
        q[i] = match child {
            Some(c) => {
                let d = to_armature.transform_vector3(joints[c].head - joints[i].head);
                Quat::from_rotation_arc(Vec3::Y, d.normalize())
            }
            None => joints[i].parent.map_or(Quat::IDENTITY, |p| q[p]),
        };
    }
    q
}

/// The weights of one vertex on the rig: the walker's, the chest's split between the two
/// upper spine joints by height, the fingers' and thumb's spread over their joints by where
/// the vertex lies, then the largest [`MAX_INFLUENCES`] kept and renormalised.
fn reweigh(w: &Walker, joints: &[Joint], p: Vec3, weights: &[Influence]) -> Vec<Influence> {
    let index = |name: &str| {
        joints
            .iter()
            .position(|j| j.name == format!("mixamorig:{name}"))
            .expect("a joint of the rig")
    };
    let mut out: Vec<(usize, f32)> = Vec::new();
    let put = |out: &mut Vec<(usize, f32)>, j: usize, x: f32| {
        if x <= 0.0 {
            return;
        }
        match out.iter_mut().find(|e| e.0 == j) {
            Some(e) => e.1 += x,
            None => out.push((j, x)),
        }
    };
    for inf in weights {
        let name = &w.model.skeleton.nodes[inf.bone as usize].name;
        let (bone, side) = match name.rsplit_once('_') {
            Some((b, "l")) => (b, "Left"),
            Some((b, "r")) => (b, "Right"),
            _ => (name.as_str(), ""),
        };
        let x = inf.weight;
        match bone {
            "chest" => {
                let (lo, hi) = (w.head("chest").y, w.head("neck").y);
                let t = ((p.y - lo) / (hi - lo)).clamp(0.0, 1.0);
                put(&mut out, index("Spine1"), x * (1.0 - t));
                put(&mut out, index("Spine2"), x * t);
            }
            "fingers" | "thumb" => {
                // Blend between the two nearest joints of the nearest finger.
                let names: Vec<String> = if bone == "thumb" {
                    vec![format!("{side}HandThumb")]
                } else {
                    ["Index", "Middle", "Ring", "Pinky"]
                        .iter()
                        .map(|f| format!("{side}Hand{f}"))
                        .collect()
                };
                let finger = names
                    .iter()
                    .min_by(|a, b| {
                        let da = joints[index(&format!("{a}1"))].head.distance(p);
                        let db = joints[index(&format!("{b}1"))].head.distance(p);
                        da.total_cmp(&db)
                    })
                    .expect("four fingers");
                let chain: Vec<usize> = (1..=3).map(|k| index(&format!("{finger}{k}"))).collect();
                let end = joints[index(&format!("{finger}4"))].head;
                let (a, b) = (joints[chain[0]].head, end);
                let s = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0) * 3.0;
                let k = (s.floor() as usize).min(2);
                let t = s - k as f32;
                put(&mut out, chain[k], x * (1.0 - t));
                if k + 1 < 3 {
                    put(&mut out, chain[k + 1], x * t);
                } else {
                    put(&mut out, chain[k], x * t);
                }
            }
            _ => {
                let target = joints
                    .iter()
                    .position(|j| j.follows == Some(inf.bone as usize))
                    .expect("every walker bone has a joint");
                put(&mut out, target, x);
            }
        }
    }
    out.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    out.truncate(MAX_INFLUENCES);
    let total: f32 = out.iter().map(|e| e.1).sum();
    out.sort_by_key(|e| e.0);
    out.iter()
        .map(|&(j, x)| Influence {
            bone: j as u32,
            weight: x / total,
        })
        .collect()
}

/// The rig's nodes in a document: the armature first, then the joints (joint `i` is node
/// `i + 1`), each oriented along its bone.
fn rig_nodes(doc: &mut Document, joints: &[Joint]) -> (Vec<Mat4>, Vec<Quat>) {
    let a = Mat4::from(armature().matrix());
    let to_armature = a.inverse();
    let q = orientations(joints, &to_armature);
    let arm = doc.node("Armature", None, armature());
    // Each joint's transform in the armature's space, and its local one from its parent's.
    let frames: Vec<Mat4> = (0..joints.len())
        .map(|i| {
            Mat4::from_rotation_translation(q[i], to_armature.transform_point3(joints[i].head))
        })
        .collect();
    for (i, jt) in joints.iter().enumerate() {
        let local = match jt.parent {
            Some(p) => frames[p].inverse() * frames[i],
            None => frames[i],
        };
        let (_, rotation, translation) = local.to_scale_rotation_translation();
        doc.node(
            &jt.name,
            Some(jt.parent.map_or(arm, |p| p + 1)),
            Trs {
                translation,
                rotation,
                scale: Vec3::ONE,
            },
        );
    }
    (frames, q)
}

/// The walker's clip `clip` on the rig, keyed where the walker's keys are: each joint turned
/// as the walker bone it follows turns, the hips carried where the walker's go.
fn retarget(w: &Walker, joints: &[Joint], q: &[Quat], clip: &Clip, name: &str) -> Clip {
    let skel = &w.model.skeleton;
    let turn = armature().rotation;
    let times = clip.channels[0].times.clone();
    let mut rotations: Vec<Vec<Vec4>> = vec![Vec::new(); joints.len()];
    let mut hips: Vec<Vec4> = Vec::new();
    for &t in &times {
        let g = crate::anim::bone_matrices(skel, Some(clip), t);
        // The armature-space orientation of every joint in this pose: its bone's turn from
        // the T-pose (the walker's clips turn its bones from its A-pose, where they are
        // unturned) applied to its rest orientation.
        let posed: Vec<Quat> = (0..joints.len())
            .map(|i| {
                let b = joints[i]
                    .follows
                    .expect("every joint follows a walker bone");
                let world = Quat::from_mat3a(&g[b].matrix3).normalize();
                let bound = Quat::from_mat3a(&w.tpose[b].matrix3).normalize();
                turn.inverse() * world * bound.inverse() * turn * q[i]
            })
            .collect();
        for i in 0..joints.len() {
            let local = match joints[i].parent {
                Some(p) => posed[p].inverse() * posed[i],
                None => posed[i],
            };
            let mut v = Vec4::from(local.normalize());
            if let Some(prev) = rotations[i].last()
                && prev.dot(v) < 0.0
            {
                v = -v;
            }
            rotations[i].push(v);
        }
        let at = armature().matrix().inverse();
        let h = g[joints[0].follows.expect("the hips follow the walker's")].translation;
        hips.push(at.transform_point3(Vec3::from(h)).extend(0.0));
    }
    let mut channels: Vec<Channel> = rotations
        .into_iter()
        .enumerate()
        .map(|(i, values)| Channel {
            node: i as u32 + 1,
            target: ChannelTarget::Rotation,
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values,
        })
        .collect();
    channels.push(Channel {
        node: 1,
        target: ChannelTarget::Translation,
        interpolation: Interpolation::Linear,
        times,
        values: hips,
    });
    Clip {
        name: name.into(),
        duration: clip.duration,
        channels,
        ground_speed: clip.ground_speed,
    }
}

/// A clip of two keys a frame apart, every joint at rest: what a service sends as a T-pose.
fn t_pose(doc: &Document, joints: &[Joint]) -> Clip {
    let times = vec![0.0, 1.0 / 30.0];
    let mut channels: Vec<Channel> = (0..joints.len())
        .map(|i| {
            let r = Vec4::from(doc.nodes[i + 1].rest.rotation);
            Channel {
                node: i as u32 + 1,
                target: ChannelTarget::Rotation,
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values: vec![r, r],
            }
        })
        .collect();
    let h = doc.nodes[1].rest.translation.extend(0.0);
    channels.push(Channel {
        node: 1,
        target: ChannelTarget::Translation,
        interpolation: Interpolation::Linear,
        times: times.clone(),
        values: vec![h, h],
    });
    Clip {
        name: "T-Pose".into(),
        duration: times[1],
        channels,
        ground_speed: 0.0,
    }
}

/// The character's file.
pub fn mocap() -> Document {
    let w = Walker::new();
    let joints = joints(&w);
    let mut doc = Document {
        generator: "lodlab gen-assets (mocap)".into(),
        materials: w.model.materials.clone(),
        ..Default::default()
    };
    let (frames, _) = rig_nodes(&mut doc, &joints);
    let to_armature = Mat4::from(armature().matrix()).inverse();
    let src = &w.model.mesh;
    let mut mesh = SkinnedMesh::empty();
    for v in 0..src.vertex_count() {
        let (p, n) = w.vertex(v);
        mesh.positions.push(to_armature.transform_point3(p));
        mesh.normals
            .push(to_armature.transform_vector3(n).normalize());
        mesh.uvs.push(src.uvs[v]);
        mesh.materials.push(src.materials[v]);
        mesh.influences
            .extend(reweigh(&w, &joints, p, src.influences_of(v)));
        mesh.influence_offsets.push(mesh.influences.len() as u32);
    }
    mesh.indices = src.indices.clone();
    doc.meshes.push(DocMesh {
        name: "Body".into(),
        primitives: vec![DocPrimitive {
            mesh,
            material: Some(0),
            targets: Vec::new(),
        }],
    });
    doc.skins.push(DocSkin {
        joints: (1..=joints.len()).collect(),
        // The vertices are in the armature's space: a joint's inverse bind matrix undoes its
        // frame there.
        // Inverted as affine maps, so the last row is exactly (0, 0, 0, 1), as the validator
        // requires of an inverse bind matrix.
        inverse_bind: frames
            .iter()
            .map(|f| Mat4::from(Affine3A::from_mat4(*f).inverse()))
            .collect(),
    });
    let body = doc.node("Body", None, Trs::IDENTITY);
    doc.nodes[body].mesh = Some(0);
    doc.nodes[body].skin = Some(0);
    doc.clips = vec![t_pose(&doc, &joints)];
    doc
}

/// The walk sent apart from the character: the same nodes, the walker's walk on them, no mesh.
pub fn mocap_walk() -> Document {
    let w = Walker::new();
    let joints = joints(&w);
    let mut doc = Document {
        generator: "lodlab gen-assets (mocap-walk)".into(),
        ..Default::default()
    };
    let (_, q) = rig_nodes(&mut doc, &joints);
    let walk = w
        .model
        .clips
        .iter()
        .find(|c| c.name == "walk")
        .expect("the walker walks");
    doc.clips = vec![retarget(&w, &joints, &q, walk, "Walking")];
    doc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rig_has_65_joints_and_four_influences_at_most() {
        let doc = mocap();
        assert_eq!(doc.skins[0].joints.len(), 65);
        let m = &doc.meshes[0].primitives[0].mesh;
        let most = (0..m.vertex_count())
            .map(|v| m.influences_of(v).len())
            .max()
            .unwrap();
        assert_eq!(most, MAX_INFLUENCES);
        // Some vertices blend three or more finger joints and hand.
        let fingers: usize = (0..m.vertex_count())
            .filter(|&v| {
                m.influences_of(v)
                    .iter()
                    .filter(|i| doc.nodes[i.bone as usize + 1].name.contains("Hand"))
                    .count()
                    >= 3
            })
            .count();
        assert!(fingers > 20, "{fingers} vertices blend three hand joints");
        // Bound in place: every joint's world frame times its inverse bind matrix is the
        // armature's transform.
        let a = Mat4::from(armature().matrix());
        for (k, &j) in doc.skins[0].joints.iter().enumerate() {
            let m = doc.world(j) * doc.skins[0].inverse_bind[k];
            assert!(m.abs_diff_eq(a, 1e-4), "joint {k}: {m:?}");
        }
    }
}
