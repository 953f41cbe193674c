//! A glTF file's meshes read into one skinned mesh: every primitive drawn by a node the skin
//! (or, for a rigid model, the scene) binds, its attributes read, checked and welded, texture
//! transforms and materials applied; `MSFT_lod`'s coarser levels left out.

use crate::geometry::weld::{compute_normals, weld_map};
use crate::model::{AlphaMode, Influence, Material, Rgba8Image, SkinnedMesh};
use glam::{Mat4, Vec2, Vec3};
use gltf::mesh::Mode;
use std::collections::{BTreeMap, HashMap, HashSet};

/// The elements of vertex attribute `$accessor`, `$n` floats each, whatever its component
/// type: `KHR_mesh_quantization` (what gltfpack writes) allows signed and unsigned 8- and
/// 16-bit integers, normalised (mapped to [-1, 1] or [0, 1] as the glTF specification says)
/// or not (their values). `None` for a component type no attribute may have.
macro_rules! read_floats {
    ($accessor:expr, $buffer:expr, $n:literal) => {{
        use gltf::accessor::{DataType, Iter};
        let a = $accessor;
        let normalized = a.normalized();
        let convert = |c: f32, scale: f32| {
            if normalized { (c / scale).max(-1.0) } else { c }
        };
        match a.data_type() {
            DataType::F32 => Iter::<[f32; $n]>::new(a, $buffer).map(|it| it.collect::<Vec<_>>()),
            DataType::I8 => Iter::<[i8; $n]>::new(a, $buffer)
                .map(|it| it.map(|v| v.map(|c| convert(c as f32, 127.0))).collect()),
            DataType::U8 => Iter::<[u8; $n]>::new(a, $buffer)
                .map(|it| it.map(|v| v.map(|c| convert(c as f32, 255.0))).collect()),
            DataType::I16 => Iter::<[i16; $n]>::new(a, $buffer)
                .map(|it| it.map(|v| v.map(|c| convert(c as f32, 32767.0))).collect()),
            DataType::U16 => Iter::<[u16; $n]>::new(a, $buffer)
                .map(|it| it.map(|v| v.map(|c| convert(c as f32, 65535.0))).collect()),
            DataType::U32 => None,
        }
    }};
}

/// Per-primitive vertex data before welding.
pub(crate) struct RawPrimitive {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Vec<Vec2>,
    influences: Vec<Vec<Influence>>,
    triangles: Vec<[u32; 3]>,
    indexed: bool,
}

/// `KHR_texture_transform` baked into texture coordinates: uv′ = T·R·S·uv, T the offset, R
/// the rotation (counter-clockwise, in radians), S the scale, as the extension defines them.
/// gltfpack writes quantised texture coordinates with the transform that maps them back.
pub(crate) fn apply_texture_transform(
    uvs: &mut [Vec2],
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
) {
    let (sin, cos) = rotation.sin_cos();
    for uv in uvs {
        let (x, y) = (uv.x * scale[0], uv.y * scale[1]);
        *uv = Vec2::new(
            cos * x + sin * y + offset[0],
            -sin * x + cos * y + offset[1],
        );
    }
}

/// The nodes that `MSFT_lod` names as lower levels of detail of another node: a reader takes
/// the highest level only, as one without the extension would (lodlab makes its own levels).
pub(crate) fn msft_lod_lower_levels(doc: &gltf::Document) -> Vec<usize> {
    doc.nodes()
        .filter_map(|n| {
            n.extensions()?
                .get("MSFT_lod")?
                .get("ids")?
                .as_array()
                .cloned()
        })
        .flatten()
        .filter_map(|id| id.as_u64().map(|i| i as usize))
        .collect()
}

/// How the vertices of one mesh node are bound: to the skin whose joints `joints` maps into
/// the model's bones (joint j of the skin is bone `joints[j]`), or rigidly to one bone with a
/// transform baked in: bone 0 and the node's world transform for an unskinned prop; the
/// nearest joint above the node, and the transform into that bone's bind space, for a part
/// hanging from a skeleton (a helmet on the head bone).
pub(crate) enum Binding<'m> {
    /// A skin: the bone of each of its joints, and the transform that takes its vertices into
    /// the space the merged skeleton's bones bind (the identity but for a mesh bound in a
    /// space of its own, see `merge_skins` in [`super::gltf`]).
    Skin(&'m [u32], Mat4),
    Rigid(Mat4, u32),
}

impl Binding<'_> {
    /// A key equal for bindings that put a mesh in the same place: the same skin (a skinned
    /// mesh's node transform does not move it), or the same bone and transform.
    fn key(&self) -> BindingKey {
        match self {
            Binding::Skin(map, _) => BindingKey::Skin(map.as_ptr() as usize),
            Binding::Rigid(m, bone) => {
                BindingKey::Rigid(*bone, m.to_cols_array().map(|x| (x + 0.0).to_bits()))
            }
        }
    }
}

/// A primitive's vertex accessors: each attribute's name and accessor, sorted.
pub(crate) type VertexAccessors = Vec<(String, usize)>;

/// What a primitive draws and where: two equal ones draw the same triangles in one place.
#[derive(PartialEq, Eq, Hash)]
pub(crate) struct DrawnPrimitive {
    attributes: VertexAccessors,
    indices: Option<usize>,
    mode: u32,
    material: Option<usize>,
    place: BindingKey,
}

/// Where a binding puts a primitive, hashable: a skin (by its joint map, which the import
/// holds for as long as the meshes are read), or a bone and a transform.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum BindingKey {
    Skin(usize),
    Rigid(u32, [u32; 16]),
}

/// The meshes of `nodes` (a mesh that two nodes draw in one place once, in two places twice),
/// all their primitives merged into one mesh (normals
/// computed where a primitive has none), and the materials they use. Morph targets are left
/// out with one warning in `warnings`: the base shape is drawn.
pub(crate) fn read_meshes(
    nodes: &[(gltf::Node, Binding)],
    buffers: &[gltf::buffer::Data],
    images: &[Option<Rgba8Image>],
    warnings: &mut Vec<String>,
) -> Result<(SkinnedMesh, Vec<Material>), String> {
    let buffer = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
    let mut material_slots: BTreeMap<Option<usize>, u16> = BTreeMap::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut mesh = SkinnedMesh::default();
    let mut needs_normals: Vec<bool> = Vec::new();
    // Where the vertices of each set of vertex accessors went (and how many), by where they
    // are drawn and in which material.
    let mut vertex_bases: HashMap<(VertexAccessors, BindingKey, u16), (u32, usize)> =
        HashMap::new();
    // Primitives read, by their accessors, mode and material and where they are drawn: one
    // drawn again in the same place (a mesh on a second node of the same skin, or of the same
    // transform; the same primitive listed again, over one accessor, thousands of times)
    // would only repeat every triangle exactly, on top of itself.
    let mut drawn: HashSet<DrawnPrimitive> = HashSet::new();
    let mut repeated = 0usize;
    let mut morphed = 0;
    for (node, binding) in nodes {
        let Some(m) = node.mesh() else { continue };
        for prim in m.primitives() {
            let (attributes, this) = drawn_primitive(&prim, binding);
            if !drawn.insert(this) {
                repeated += 1;
                continue;
            }
            let label = format!("mesh {} primitive {}", m.index(), prim.index());
            if prim.morph_targets().len() > 0 {
                morphed += 1;
            }
            let material = prim.material();
            let slot = material_slot(&material, images, &mut material_slots, &mut materials)?;
            let (uv_set, transform) = base_colour_uvs(&material);
            let joints = match binding {
                Binding::Skin(map, _) => Some(map.len()),
                Binding::Rigid(..) => None,
            };
            let mut raw = read_primitive(&prim, buffer, uv_set, joints, &label)?;
            apply_material_transform(&mut raw, transform, &label)?;
            bind(&mut raw, binding);
            // Primitives over the same vertex accessors, drawn in one place in one material,
            // share their vertices: an exporter's layout (one vertex buffer, index buffers
            // per part).
            let key = (attributes, binding.key(), slot);
            let shared = vertex_bases.get(&key).copied();
            let base = append_primitive(&mut mesh, &mut needs_normals, raw, slot, shared);
            vertex_bases.entry(key).or_insert(base);
        }
    }
    if morphed > 0 {
        warnings.push(format!(
            "morph targets are left out on {morphed} primitive(s) (the base shape is drawn)"
        ));
    }
    if repeated > 0 {
        log::info!("{repeated} primitive(s) drawn again where they were already drawn read once");
    }
    finish_mesh(&mut mesh, &needs_normals)?;

    Ok((mesh, materials))
}

/// A primitive's vertex accessors (sorted), and what it draws where under `binding`: the key
/// by which a primitive drawn again in the same place is read once.
fn drawn_primitive(prim: &gltf::Primitive, binding: &Binding) -> (VertexAccessors, DrawnPrimitive) {
    let mut attributes: VertexAccessors = prim
        .attributes()
        .map(|(s, a)| (s.to_string(), a.index()))
        .collect();
    attributes.sort();
    let this = DrawnPrimitive {
        attributes: attributes.clone(),
        indices: prim.indices().map(|a| a.index()),
        mode: prim.mode().as_gl_enum(),
        material: prim.material().index(),
        place: binding.key(),
    };
    (attributes, this)
}

/// The model's material slot of a glTF material, converted and added to `materials` the first
/// time a primitive uses it: a vertex stores its material as a `u16`.
fn material_slot(
    material: &gltf::Material,
    images: &[Option<Rgba8Image>],
    material_slots: &mut BTreeMap<Option<usize>, u16>,
    materials: &mut Vec<Material>,
) -> Result<u16, String> {
    Ok(match material_slots.get(&material.index()) {
        Some(&s) => s,
        None => {
            let s = u16::try_from(materials.len())
                .map_err(|_| "more than 65535 materials".to_string())?;
            materials.push(convert_material(material, images)?);
            material_slots.insert(material.index(), s);
            s
        }
    })
}

/// The texture coordinate set a material's base colour texture reads (its
/// `KHR_texture_transform` may name another), and that transform.
fn base_colour_uvs<'a>(
    material: &gltf::Material<'a>,
) -> (u32, Option<gltf::texture::TextureTransform<'a>>) {
    let base_colour = material.pbr_metallic_roughness().base_color_texture();
    let transform = base_colour.as_ref().and_then(|t| t.texture_transform());
    let uv_set = transform
        .as_ref()
        .and_then(|t| t.tex_coord())
        .or(base_colour.as_ref().map(|t| t.tex_coord()))
        .unwrap_or(0);
    (uv_set, transform)
}

/// A material's `KHR_texture_transform`, checked finite, baked into a primitive's texture
/// coordinates.
fn apply_material_transform(
    raw: &mut RawPrimitive,
    transform: Option<gltf::texture::TextureTransform>,
    label: &str,
) -> Result<(), String> {
    if let Some(t) = &transform {
        let finite =
            t.offset().iter().chain(&t.scale()).all(|v| v.is_finite()) && t.rotation().is_finite();
        if !finite {
            return Err(format!(
                "{label}: its material's KHR_texture_transform is not finite"
            ));
        }
    }
    if let Some(t) = transform {
        apply_texture_transform(&mut raw.uvs, t.offset(), t.rotation(), t.scale());
    }
    Ok(())
}

/// A primitive's vertices bound as `binding` says: a skin's joints mapped to the model's
/// bones, or a rigid part given its bone and moved by its transform.
fn bind(raw: &mut RawPrimitive, binding: &Binding) {
    match binding {
        Binding::Skin(map, into) => {
            for inf in raw.influences.iter_mut().flatten() {
                inf.bone = map[inf.bone as usize];
            }
            if *into != Mat4::IDENTITY {
                transform(raw, into);
            }
        }
        Binding::Rigid(world, bone) => {
            for inf in raw.influences.iter_mut().flatten() {
                inf.bone = *bone;
            }
            transform(raw, world);
        }
    }
}

/// Moves a primitive's vertices by `world`: positions, normals, and the triangles' winding
/// where it mirrors.
fn transform(raw: &mut RawPrimitive, world: &Mat4) {
    let normal_matrix = glam::Mat3::from_mat4(*world).inverse().transpose();
    for p in &mut raw.positions {
        *p = world.transform_point3(*p);
    }
    for n in raw.normals.iter_mut().flatten() {
        *n = (normal_matrix * *n).normalize_or(Vec3::Y);
    }
    if world.determinant() < 0.0 {
        // A mirroring transform turns the triangles inside out.
        raw.triangles.iter_mut().for_each(|t| t.swap(1, 2));
    }
}

/// The merged mesh made ready: normals computed where a primitive had none, what no triangle
/// draws dropped, and a mesh that would draw nothing refused.
fn finish_mesh(mesh: &mut SkinnedMesh, needs_normals: &[bool]) -> Result<(), String> {
    if needs_normals.iter().any(|&n| n) {
        compute_normals(mesh, needs_normals);
    }
    // Degenerate and repeated triangles, and the vertices only they used (or none did), go
    // before anything counts vertices or builds animation space from them.
    let (triangles, vertices) = mesh.drop_unused();
    if triangles + vertices > 0 {
        log::info!(
            "{triangles} degenerate or repeated triangle(s) and {vertices} vertex(es) no \
             triangle uses left out"
        );
    }
    if mesh.triangle_count() == 0 {
        return Err("the skinned mesh has no triangles".into());
    }
    // Two corners at one point with one skin stay at one point in every pose: such a triangle
    // never covers a pixel, and animation space welds the two into one vertex. A mesh of
    // nothing else would bake to levels of no triangles (found by the `random_mesh` fuzzer).
    if !mesh.draws() {
        return Err(
            "the skinned mesh has no triangles that draw (each has two corners at one point)"
                .into(),
        );
    }
    Ok(())
}

pub(crate) fn read_primitive<'a, 's, F>(
    prim: &'a gltf::Primitive<'a>,
    buffer: F,
    uv_set: u32,
    joint_count: Option<usize>,
    label: &str,
) -> Result<RawPrimitive, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let reader = prim.reader(buffer.clone());
    let (positions, normals, uvs) = read_vertices(prim, buffer, uv_set, label)?;
    let n = positions.len();

    // Skin influences from every JOINTS_n / WEIGHTS_n pair; a rigid mesh (no skin) follows
    // bone 0 alone.
    let Some(joint_count) = joint_count else {
        let influences = vec![
            vec![Influence {
                bone: 0,
                weight: 1.0
            }];
            n
        ];
        return finish_primitive(prim, &reader, positions, normals, uvs, influences, label);
    };
    let mut influences = read_influences(&reader, n, joint_count, label)?;
    normalise_influences(&mut influences, label)?;
    finish_primitive(prim, &reader, positions, normals, uvs, influences, label)
}

/// A primitive's positions, normals (if any) and texture coordinates, before influences.
type Vertices = (Vec<Vec3>, Option<Vec<Vec3>>, Vec<Vec2>);

/// A primitive's positions, normals (if any) and texture coordinates of set `uv_set` (zero
/// where it has none), checked finite and of one count.
fn read_vertices<'a, 's, F>(
    prim: &'a gltf::Primitive<'a>,
    buffer: F,
    uv_set: u32,
    label: &str,
) -> Result<Vertices, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let attribute = |s: gltf::Semantic| prim.get(&s);
    let positions: Vec<Vec3> = attribute(gltf::Semantic::Positions)
        .and_then(|a| read_floats!(a, buffer.clone(), 3))
        .ok_or_else(|| format!("{label}: has no POSITION attribute"))?
        .into_iter()
        .map(Vec3::from)
        .collect();
    let n = positions.len();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("{label}: vertex {i} has a non-finite position"));
    }
    let normals: Option<Vec<Vec3>> = attribute(gltf::Semantic::Normals)
        .and_then(|a| read_floats!(a, buffer.clone(), 3))
        .map(|ns| {
            ns.into_iter()
                .map(|n| Vec3::from(n).normalize_or_zero())
                .collect()
        });
    if let Some(ns) = &normals {
        if ns.len() != n {
            return Err(format!("{label}: NORMAL count differs from POSITION count"));
        }
        if let Some(i) = ns.iter().position(|v| !v.is_finite()) {
            return Err(format!("{label}: vertex {i} has a non-finite normal"));
        }
    }
    let uvs: Vec<Vec2> = match attribute(gltf::Semantic::TexCoords(uv_set))
        .and_then(|a| read_floats!(a, buffer.clone(), 2))
    {
        Some(uvs) => uvs.into_iter().map(Vec2::from).collect(),
        None => vec![Vec2::ZERO; n],
    };
    if uvs.len() != n {
        return Err(format!(
            "{label}: TEXCOORD_{uv_set} count differs from POSITION count"
        ));
    }
    if let Some(i) = uvs.iter().position(|v| !v.is_finite()) {
        return Err(format!(
            "{label}: vertex {i} has a non-finite texture coordinate"
        ));
    }
    Ok((positions, normals, uvs))
}

/// The skin influences of a primitive's `n` vertices from every JOINTS_n / WEIGHTS_n pair,
/// checked (weights finite and non-negative, joints in the skin's `joint_count`), the
/// weights of one joint summed; zero weights left out. Not yet normalised.
fn read_influences<'a, 's, F>(
    reader: &gltf::mesh::Reader<'a, 's, F>,
    n: usize,
    joint_count: usize,
    label: &str,
) -> Result<Vec<Vec<Influence>>, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let mut influences: Vec<Vec<Influence>> = vec![Vec::new(); n];
    let mut set = 0;
    loop {
        let (j, w) = (reader.read_joints(set), reader.read_weights(set));
        let (j, w) = match (j, w) {
            (None, None) => break,
            (Some(j), Some(w)) => (j, w),
            _ => {
                return Err(format!(
                    "{label}: JOINTS_{set} and WEIGHTS_{set} must come together"
                ));
            }
        };
        let j: Vec<[u16; 4]> = j.into_u16().collect();
        let w: Vec<[f32; 4]> = w.into_f32().collect();
        if j.len() != n || w.len() != n {
            return Err(format!(
                "{label}: JOINTS_{set}/WEIGHTS_{set} count differs from POSITION count"
            ));
        }
        for v in 0..n {
            for k in 0..4 {
                let (bone, weight) = (j[v][k] as u32, w[v][k]);
                if weight.is_nan() {
                    return Err(format!("{label}: vertex {v} has a NaN weight"));
                }
                if !weight.is_finite() || weight < 0.0 {
                    return Err(format!(
                        "{label}: vertex {v} has an invalid weight {weight}"
                    ));
                }
                if weight == 0.0 {
                    continue;
                }
                if bone as usize >= joint_count {
                    return Err(format!(
                        "{label}: vertex {v} uses joint index {bone}, but the skin has only {joint_count} joints"
                    ));
                }
                match influences[v].iter_mut().find(|i| i.bone == bone) {
                    // Summed in f64 so that two huge weights of one joint stay finite.
                    Some(i) => {
                        i.weight = (i.weight as f64 + weight as f64).min(f32::MAX as f64) as f32
                    }
                    None => influences[v].push(Influence { bone, weight }),
                }
            }
        }
        set += 1;
    }
    if set == 0 {
        return Err(format!(
            "{label}: has no JOINTS_0/WEIGHTS_0 skin attributes"
        ));
    }
    Ok(influences)
}

/// Every vertex's weights scaled to sum to 1, and its influences in bone order; a vertex of
/// no weight at all is refused.
fn normalise_influences(influences: &mut [Vec<Influence>], label: &str) -> Result<(), String> {
    for (v, inf) in influences.iter_mut().enumerate() {
        let total: f32 = inf.iter().map(|i| i.weight).sum();
        if total <= 0.0 {
            return Err(format!("{label}: vertex {v} has all-zero skin weights"));
        }
        if total.is_finite() {
            for i in inf.iter_mut() {
                i.weight /= total;
            }
        } else {
            // Weights near f32::MAX (3e38 + 3e38) overflow an f32 sum to infinity, which would
            // turn every weight to zero: normalise those in f64.
            let total: f64 = inf.iter().map(|i| i.weight as f64).sum();
            for i in inf.iter_mut() {
                i.weight = (i.weight as f64 / total) as f32;
            }
        }
        inf.sort_by_key(|i| i.bone);
    }
    Ok(())
}

/// A primitive's triangles (from its indices and mode) with its vertices read so far.
pub(crate) fn finish_primitive<'a, 's, F>(
    prim: &'a gltf::Primitive<'a>,
    reader: &gltf::mesh::Reader<'a, 's, F>,
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Vec<Vec2>,
    influences: Vec<Vec<Influence>>,
    label: &str,
) -> Result<RawPrimitive, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let n = positions.len();
    let indices: Option<Vec<u32>> = reader.read_indices().map(|i| i.into_u32().collect());
    let indexed = indices.is_some();
    let index_list: Vec<u32> = indices.unwrap_or_else(|| (0..n as u32).collect());
    if let Some(&bad) = index_list.iter().find(|&&i| i as usize >= n) {
        return Err(format!(
            "{label}: index {bad} is out of range ({n} vertices)"
        ));
    }
    let triangles: Vec<[u32; 3]> = match prim.mode() {
        Mode::Triangles => index_list
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
        Mode::TriangleStrip => (0..index_list.len().saturating_sub(2))
            .map(|i| {
                let (a, b, c) = (index_list[i], index_list[i + 1], index_list[i + 2]);
                if i % 2 == 0 { [a, b, c] } else { [b, a, c] }
            })
            .collect(),
        Mode::TriangleFan => (1..index_list.len().saturating_sub(1))
            .map(|i| [index_list[0], index_list[i], index_list[i + 1]])
            .collect(),
        other => {
            return Err(format!(
                "{label}: primitive mode {other:?} is not supported (triangles only)"
            ));
        }
    };
    Ok(RawPrimitive {
        positions,
        normals,
        uvs,
        influences,
        triangles,
        indexed,
    })
}

/// Merges unindexed vertices that share position, normal, UV and influences (see `weld`).
pub(crate) fn weld(raw: RawPrimitive) -> RawPrimitive {
    let rep = weld_map(&raw.positions, |a, b| {
        raw.uvs[a] == raw.uvs[b]
            && raw.influences[a] == raw.influences[b]
            && raw
                .normals
                .as_ref()
                .is_none_or(|n| n[a].normalize_or_zero().dot(n[b].normalize_or_zero()) > 0.9999)
    });
    let mut new_index = vec![u32::MAX; rep.len()];
    let mut kept = Vec::new();
    for (v, &r) in rep.iter().enumerate() {
        if r as usize == v {
            new_index[v] = kept.len() as u32;
            kept.push(v);
        }
    }
    let pick = |v: u32| new_index[rep[v as usize] as usize];
    RawPrimitive {
        positions: kept.iter().map(|&v| raw.positions[v]).collect(),
        normals: raw
            .normals
            .as_ref()
            .map(|n| kept.iter().map(|&v| n[v]).collect()),
        uvs: kept.iter().map(|&v| raw.uvs[v]).collect(),
        influences: kept.iter().map(|&v| raw.influences[v].clone()).collect(),
        triangles: raw.triangles.iter().map(|t| t.map(pick)).collect(),
        indexed: true,
    }
}

/// Appends a primitive's vertices and triangles; with `shared`, where the same vertices were
/// appended before (their first index and count), only its triangles, onto those. Returns
/// where its vertices are.
pub(crate) fn append_primitive(
    mesh: &mut SkinnedMesh,
    needs_normals: &mut Vec<bool>,
    raw: RawPrimitive,
    material: u16,
    shared: Option<(u32, usize)>,
) -> (u32, usize) {
    let raw = if raw.indexed { raw } else { weld(raw) };
    if let Some((base, count)) = shared
        && count == raw.positions.len()
    {
        for t in raw.triangles {
            mesh.indices.extend(t.iter().map(|&i| i + base));
        }
        return (base, count);
    }
    let base = mesh.positions.len() as u32;
    let has_normals = raw.normals.is_some();
    if mesh.influence_offsets.is_empty() {
        mesh.influence_offsets.push(0);
    }
    for v in 0..raw.positions.len() {
        mesh.positions.push(raw.positions[v]);
        mesh.normals.push(
            raw.normals
                .as_ref()
                .map(|n| n[v].normalize_or(Vec3::Y))
                .unwrap_or(Vec3::Y),
        );
        mesh.uvs.push(raw.uvs[v]);
        mesh.materials.push(material);
        mesh.influences.extend_from_slice(&raw.influences[v]);
        mesh.influence_offsets.push(mesh.influences.len() as u32);
        needs_normals.push(!has_normals);
    }
    // Triangles that welding (or the file) made degenerate go later, with the rest
    // (`SkinnedMesh::drop_unused`).
    let count = raw.positions.len();
    for t in raw.triangles {
        mesh.indices.extend(t.iter().map(|&i| i + base));
    }
    (base, count)
}

pub(crate) fn convert_material(
    material: &gltf::Material,
    images: &[Option<Rgba8Image>],
) -> Result<Material, String> {
    let pbr = material.pbr_metallic_roughness();
    let texture = match pbr.base_color_texture() {
        Some(info) => {
            let index = info.texture().source().index();
            let image = images
                .get(index)
                .and_then(Option::as_ref)
                .ok_or_else(|| format!("material refers to missing image {index}"))?;
            Some(image.clone())
        }
        None => None,
    };
    let base_color = pbr.base_color_factor();
    if base_color.iter().any(|c| !c.is_finite()) {
        return Err("a material has a non-finite base colour".into());
    }
    let alpha_cutoff = material.alpha_cutoff().unwrap_or(0.5);
    if !alpha_cutoff.is_finite() || alpha_cutoff < 0.0 {
        return Err(format!(
            "a material has an invalid alphaCutoff {alpha_cutoff}"
        ));
    }
    Ok(Material {
        name: material
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("material{}", material.index().unwrap_or(0))),
        base_color,
        texture,
        alpha_mode: match material.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask,
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        alpha_cutoff,
        double_sided: material.double_sided(),
        // A file's material is a surface, whatever it is called.
        role: crate::model::MaterialRole::Surface,
    })
}
