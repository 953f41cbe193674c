//! The second hardening round: small files that are valid but odd (one triangle, a fan, a
//! vertex no triangle uses, primitives sharing one vertex buffer), files that expand far past
//! their size (accessors without data, compressed views decoded many times, primitives and
//! meshes repeated over one accessor, clips sharing a sampler, textures shared by materials),
//! files that name pipes, devices or files outside their folder, and data whose values drive a
//! loop's trip count. Each goes through the command line as a user meets it: exit 1 and one
//! line naming the file and the problem, or a bake that succeeds, within a minute.
//!
//! `LODLAB_HARDENING_DIR=DIR cargo test --test malformed second_round` also leaves the files
//! in DIR, with `commands.txt` listing each case's command line (for `/usr/bin/time -v` runs of
//! the release build: `tools/hardening-time.sh DIR`).

use crate::common::{edit_glb, glb_of, gltf_tools, tiny_model, validate};
use lodlab::generate::glb::to_glb;
use serde_json::{Value, json};
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// What the command must give.
enum Expect {
    /// Exit 1, one line naming the file and containing this.
    Error(&'static str),
    /// Exit 0.
    Succeeds,
    /// Refused by the argument parser (exit 2) with a line containing this.
    Refused(&'static str),
}

struct Case {
    name: &'static str,
    /// The file the command names (written into the case's folder by `make`).
    file: PathBuf,
    args: Vec<String>,
    expect: Expect,
}

fn f32s(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn u32s(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// A `.glb` of this JSON (its buffer 0 set to the binary chunk) and binary chunk.
fn glb(mut json: Value, mut bin: Vec<u8>) -> Vec<u8> {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    if json.get("buffers").is_none() && !bin.is_empty() {
        json["buffers"] = json!([{}]);
    }
    if !bin.is_empty() {
        json["buffers"][0]["byteLength"] = json!(bin.len());
    }
    let bin = (!bin.is_empty()).then_some(&bin[..]);
    glb_of(&serde_json::to_vec(&json).unwrap(), bin)
}

/// A binary buffer built up of views.
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
}

impl Bin {
    fn view(&mut self, data: &[u8]) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len()}));
        self.bytes.extend_from_slice(data);
        self.views.len() - 1
    }
}

/// An unskinned mesh of these positions, drawn as `mode` with these indices (or none).
fn rigid(positions: &[[f32; 3]], indices: Option<&[u32]>, mode: u32) -> Vec<u8> {
    let mut bin = Bin::default();
    let flat: Vec<f32> = positions.iter().flatten().copied().collect();
    let pv = bin.view(&f32s(&flat));
    let (lo, hi) = bounds(positions);
    let mut accessors = vec![
        json!({"bufferView": pv, "componentType": 5126, "count": positions.len(),
        "type": "VEC3", "min": lo, "max": hi}),
    ];
    let mut primitive = json!({"attributes": {"POSITION": 0}, "mode": mode});
    if let Some(ix) = indices {
        let iv = bin.view(&u32s(ix));
        accessors.push(
            json!({"bufferView": iv, "componentType": 5125, "count": ix.len(), "type": "SCALAR"}),
        );
        primitive["indices"] = json!(1);
    }
    glb(
        json!({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}], "meshes": [{"primitives": [primitive]}],
            "accessors": accessors, "bufferViews": bin.views}),
        bin.bytes,
    )
}

fn bounds(positions: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::MAX; 3];
    let mut hi = [f32::MIN; 3];
    for p in positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// The tiny model (10 vertices, 8 triangles, 2 joints, one clip) as `.glb`.
fn tiny() -> Vec<u8> {
    to_glb(&tiny_model())
}

/// The tiny model with its JSON edited and data appended: `edit` gets the JSON and a function
/// that appends bytes as a new buffer view and returns its index.
fn tiny_with(edit: impl FnOnce(&mut Value, &mut dyn FnMut(&[u8]) -> usize)) -> Vec<u8> {
    let base = tiny();
    let parsed = gltf::binary::Glb::from_slice(&base).unwrap();
    let mut bytes = parsed.bin.unwrap().into_owned();
    let mut json: Value = serde_json::from_slice(&parsed.json).unwrap();
    let mut views: Vec<Value> = json["bufferViews"].as_array().unwrap().clone();
    {
        let mut append = |data: &[u8]| {
            while !bytes.len().is_multiple_of(4) {
                bytes.push(0);
            }
            views.push(json!({"buffer": 0, "byteOffset": bytes.len(), "byteLength": data.len()}));
            bytes.extend_from_slice(data);
            views.len() - 1
        };
        edit(&mut json, &mut append);
    }
    // Views appended by `edit` are in `views`; ones it wrote itself win.
    let edited = json["bufferViews"].as_array().unwrap().len();
    for v in views.into_iter().skip(edited) {
        json["bufferViews"].as_array_mut().unwrap().push(v);
    }
    glb(json, bytes)
}

/// A new accessor in `j`; returns its index.
fn accessor(j: &mut Value, a: Value) -> usize {
    let list = j["accessors"].as_array_mut().unwrap();
    list.push(a);
    list.len() - 1
}

fn prim(j: &mut Value) -> &mut Value {
    &mut j["meshes"][0]["primitives"][0]
}

/// A 1×1 grey PNG, or one of `side`² texels of one colour (which compresses to a few KB).
fn png(side: u32) -> Vec<u8> {
    let img = image::RgbaImage::from_pixel(side, side, image::Rgba([128, 128, 128, 255]));
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

/// A real 16×16 JPEG whose frame header (SOF0) is patched to claim `w`×`h` texels and comes
/// after `app1` bytes of APP1 data (EXIF in real files, split over as many segments as it
/// needs): its size is found only by reading past them.
fn jpeg_with_late_sof(w: u16, h: u16, app1: usize) -> Vec<u8> {
    let img = image::RgbImage::from_pixel(16, 16, image::Rgb([90, 120, 150]));
    let mut jpeg = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut jpeg),
        image::ImageFormat::Jpeg,
    )
    .unwrap();
    let sof = jpeg
        .windows(2)
        .position(|m| m == [0xFF, 0xC0])
        .expect("a baseline frame header");
    jpeg[sof + 5..sof + 7].copy_from_slice(&h.to_be_bytes());
    jpeg[sof + 7..sof + 9].copy_from_slice(&w.to_be_bytes());
    let mut b = vec![0xFF, 0xD8];
    let mut left = app1;
    while left > 0 {
        let n = left.min(65_000);
        b.extend_from_slice(&[0xFF, 0xE1]);
        b.extend_from_slice(&((n + 2) as u16).to_be_bytes());
        b.extend(std::iter::repeat_n(0u8, n));
        left -= n;
    }
    b.extend_from_slice(&jpeg[2..]);
    b
}

/// Textured materials: the tiny model's texture coordinates and `materials` materials all
/// sampling one image (`image`, of `mime`), the mesh split into that many primitives.
fn shared_texture(image: &[u8], mime: &str, materials: usize) -> Vec<u8> {
    let image = image.to_vec();
    let mime = mime.to_string();
    tiny_with(move |j, append| {
        let view = append(&image);
        j["images"] = json!([{"bufferView": view, "mimeType": mime}]);
        j["textures"] = json!([{"source": 0}]);
        j["materials"] = (0..materials)
            .map(|m| json!({"name": format!("m{m}"), "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}))
            .collect();
        let p = prim(j).clone();
        j["meshes"][0]["primitives"] = (0..materials)
            .map(|m| {
                let mut q = p.clone();
                q["material"] = json!(m);
                q
            })
            .collect();
    })
}

/// The tiny model textured by a 1×1 image, its texture coordinates spanning `extent` texture
/// widths across the strip (and a quarter of that up it): tiled that many times.
fn textured_tiny(extent: f32) -> Vec<u8> {
    tiny_with(|j, append| {
        let uvs: Vec<f32> = (0..10)
            .flat_map(|i| [(i % 2) as f32 * extent, (i / 2) as f32 * extent / 4.0])
            .collect();
        let v = append(&f32s(&uvs));
        let a = accessor(
            j,
            json!({"bufferView": v, "componentType": 5126, "count": 10, "type": "VEC2"}),
        );
        prim(j)["attributes"]["TEXCOORD_0"] = json!(a);
        j["images"] = json!([{"uri": "data:image/png;base64,".to_string() + &base64(&png(1))}]);
        j["textures"] = json!([{"source": 0}]);
        j["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    })
}

/// A sparse substitution of element 0 by one zero value of `size` bytes: what lets an
/// accessor without a buffer view claim any count (its other elements are zeros).
fn one_sparse_value(append: &mut dyn FnMut(&[u8]) -> usize, size: usize) -> Value {
    let indices = append(&u32s(&[0]));
    let values = append(&vec![0u8; size]);
    json!({"count": 1, "indices": {"bufferView": indices, "componentType": 5125},
        "values": {"bufferView": values}})
}

/// The tiny model's one primitive repeated `times` over the same accessors.
fn repeated_primitive(times: usize) -> Vec<u8> {
    edit_glb(&tiny(), |j| {
        let p = j["meshes"][0]["primitives"][0].clone();
        j["meshes"][0]["primitives"] = Value::Array(vec![p; times]);
    })
}

/// The cases, their files written into `dir` as they are added.
struct Cases<'d> {
    dir: &'d Path,
    list: Vec<Case>,
}

impl Cases<'_> {
    /// `lodlab bake --cache DIR/cache FILE`, the file written as `name` from `bytes`.
    fn add(&mut self, name: &'static str, bytes: Vec<u8>, expect: Expect) {
        self.add_with(name, bytes, &[], expect);
    }

    /// [`Cases::add`] with more arguments after the file.
    fn add_with(&mut self, name: &'static str, bytes: Vec<u8>, extra: &[&str], expect: Expect) {
        let file = self.dir.join(name);
        std::fs::write(&file, bytes).unwrap();
        let mut args: Vec<String> = vec![
            "bake".into(),
            "--cache".into(),
            self.dir.join("cache").display().to_string(),
            file.display().to_string(),
        ];
        args.extend(extra.iter().map(|a| a.to_string()));
        self.list.push(Case {
            name,
            file,
            args,
            expect,
        });
    }
}

/// Makes every case's files in `dir`.
fn cases(dir: &Path) -> Vec<Case> {
    let mut c = Cases {
        dir,
        list: Vec::new(),
    };

    // --- Valid but odd: each must bake.
    c.add(
        "one-triangle-rigid.glb",
        rigid(
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            Some(&[0, 1, 2]),
            4,
        ),
        Expect::Succeeds,
    );
    c.add(
        "one-triangle-unindexed.glb",
        rigid(
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            None,
            4,
        ),
        Expect::Succeeds,
    );
    c.add(
        "one-triangle-skinned.glb",
        tiny_with(|j, append| {
            let v = append(&u32s(&[0, 1, 3]));
            let a = accessor(
                j,
                json!({"bufferView": v, "componentType": 5125, "count": 3, "type": "SCALAR"}),
            );
            prim(j)["indices"] = json!(a);
        }),
        Expect::Succeeds,
    );
    let fan: Vec<[f32; 3]> = std::iter::once([0.0, 0.0, 0.0])
        .chain((0..7).map(|k| {
            let a = k as f32 * 0.8;
            [a.cos(), a.sin(), 0.0]
        }))
        .collect();
    c.add("fan.glb", rigid(&fan, None, 6), Expect::Succeeds);
    c.add(
        "fan-indexed.glb",
        rigid(&fan, Some(&[0, 1, 2, 3, 4, 5, 6, 7]), 6),
        Expect::Succeeds,
    );
    c.add(
        "strip.glb",
        rigid(&fan, Some(&[1, 0, 2, 3, 4, 5, 6, 7]), 5),
        Expect::Succeeds,
    );
    c.add(
        "fan-skinned.glb",
        tiny_with(|j, append| {
            let v = append(&u32s(&[0, 1, 3, 5, 7, 9, 8, 6]));
            let a = accessor(
                j,
                json!({"bufferView": v, "componentType": 5125, "count": 8, "type": "SCALAR"}),
            );
            prim(j)["indices"] = json!(a);
            prim(j)["mode"] = json!(6);
        }),
        Expect::Succeeds,
    );
    c.add(
        "unreferenced-vertices.glb",
        tiny_with(|j, append| {
            // The tube's first two triangles (the only ones using vertices 0 and 1) gone.
            let kept: Vec<u32> = vec![2, 3, 5, 2, 5, 4, 4, 5, 7, 4, 7, 6, 6, 7, 9, 6, 9, 8];
            let v = append(&u32s(&kept));
            let a = accessor(
                j,
                json!({"bufferView": v, "componentType": 5125, "count": kept.len(), "type": "SCALAR"}),
            );
            prim(j)["indices"] = json!(a);
        }),
        Expect::Succeeds,
    );
    c.add(
        "shared-vertex-accessors.glb",
        tiny_with(|j, append| {
            // Two materials, two primitives over the same attributes, each indexing half.
            let halves = [
                vec![0u32, 1, 3, 0, 3, 2, 2, 3, 5, 2, 5, 4],
                vec![4u32, 5, 7, 4, 7, 6, 6, 7, 9, 6, 9, 8],
            ];
            let mut ids = Vec::new();
            for h in &halves {
                let v = append(&u32s(h));
                ids.push(accessor(j, json!({"bufferView": v, "componentType": 5125, "count": h.len(), "type": "SCALAR"})));
            }
            j["materials"] = json!([
                {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.1, 0.1, 1.0]}},
                {"name": "blue", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.1, 0.8, 1.0]}}
            ]);
            let p = prim(j).clone();
            j["meshes"][0]["primitives"] = ids
                .iter()
                .enumerate()
                .map(|(m, &a)| {
                    let mut q = p.clone();
                    q["indices"] = json!(a);
                    q["material"] = json!(m);
                    q
                })
                .collect();
        }),
        Expect::Succeeds,
    );
    c.add(
        "channel-without-node.glb",
        edit_glb(&tiny(), |j| {
            let t = &mut j["animations"][0]["channels"][0]["target"];
            t.as_object_mut().unwrap().remove("node");
        }),
        Expect::Succeeds,
    );
    c.add(
        "mesh-on-two-nodes.glb",
        {
            let tri = rigid(
                &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                Some(&[0, 1, 2]),
                4,
            );
            edit_glb(&tri, |j| {
                j["nodes"] = json!([{"mesh": 0}, {"mesh": 0, "translation": [3.0, 0.0, 0.0]}]);
                j["scenes"][0]["nodes"] = json!([0, 1]);
            })
        },
        Expect::Succeeds,
    );
    c.add(
        "texcoords-0-to-1000.glb",
        textured_tiny(1000.0),
        Expect::Succeeds,
    );
    c.add(
        "inverse-bind-1e12.glb",
        tiny_with(|j, append| {
            let joints = j["skins"][0]["joints"].as_array().unwrap().len();
            let m: Vec<f32> = (0..joints)
                .flat_map(|_| {
                    [
                        1e12, 0.0, 0.0, 0.0, 0.0, 1e12, 0.0, 0.0, 0.0, 0.0, 1e12, 0.0, 0.0, 0.0,
                        0.0, 1.0,
                    ]
                })
                .collect();
            let v = append(&f32s(&m));
            let a = accessor(
                j,
                json!({"bufferView": v, "componentType": 5126, "count": joints, "type": "MAT4"}),
            );
            j["skins"][0]["inverseBindMatrices"] = json!(a);
        }),
        Expect::Succeeds,
    );

    // --- Panics found on files that are not valid.
    c.add(
        "channel-node-99.glb",
        edit_glb(&tiny(), |j| {
            j["animations"][0]["channels"][0]["target"]["node"] = json!(99)
        }),
        Expect::Error("node 99"),
    );
    c.add(
        "texcoords-short-unnormalised.glb",
        tiny_with(|j, append| {
            let uvs: Vec<u8> = (0..10u16)
                .flat_map(|i| [(i % 2) * 1000, (i / 2) * 250])
                .flat_map(|v| v.to_le_bytes())
                .collect();
            let v = append(&uvs);
            let a = accessor(
                j,
                json!({"bufferView": v, "componentType": 5122, "count": 10, "type": "VEC2"}),
            );
            prim(j)["attributes"]["TEXCOORD_0"] = json!(a);
        }),
        Expect::Error("KHR_mesh_quantization"),
    );

    // --- Expansion: a few bytes that claim hundreds of millions of elements.
    c.add(
        "indices-sparse-3e8.glb",
        tiny_with(|j, append| {
            let iv = append(&u32s(&[0, 1, 2]));
            let vv = append(&u32s(&[0, 1, 3]));
            let a = accessor(
                j,
                json!({"componentType": 5125, "count": 300_000_003u64, "type": "SCALAR",
                "sparse": {"count": 3, "indices": {"bufferView": iv, "componentType": 5125},
                    "values": {"bufferView": vv}}}),
            );
            prim(j)["indices"] = json!(a);
        }),
        Expect::Error("--limit triangles"),
    );
    c.add(
        "positions-sparse-2e27.glb",
        tiny_with(|j, append| {
            let sparse = one_sparse_value(append, 12);
            let a = accessor(
                j,
                json!({"componentType": 5126, "count": 1u64 << 27, "type": "VEC3",
                "min": [0.0, 0.0, 0.0], "max": [0.0, 0.0, 0.0], "sparse": sparse}),
            );
            let p = prim(j);
            p["attributes"] = json!({"POSITION": a});
            p.as_object_mut().unwrap().remove("indices");
        }),
        Expect::Error("--limit vertices"),
    );
    c.add(
        "weights-sparse-2e28.glb",
        tiny_with(|j, append| {
            let sparse = one_sparse_value(append, 16);
            let a = accessor(
                j,
                json!({"componentType": 5126, "count": 1u64 << 28, "type": "VEC4", "sparse": sparse}),
            );
            prim(j)["attributes"]["WEIGHTS_0"] = json!(a);
        }),
        Expect::Error("POSITION has 10"),
    );
    c.add(
        "primitive-repeated-3000.glb",
        repeated_primitive(3000),
        Expect::Succeeds,
    );
    c.add_with(
        "primitive-repeated-3000-limited.glb",
        repeated_primitive(3000),
        &["--limit", "triangles=20000"],
        Expect::Error("--limit triangles"),
    );
    c.add(
        "mesh-on-5000-nodes.glb",
        {
            let tri = rigid(&fan, None, 6);
            edit_glb(&tri, |j| {
                j["nodes"] = (0..5000)
                    .map(|k| json!({"mesh": 0, "translation": [(k % 100) as f32 * 2.0, (k / 100) as f32 * 2.0, 0.0]}))
                    .collect();
                j["scenes"][0]["nodes"] = (0..5000).collect();
            })
        },
        Expect::Succeeds,
    );
    c.add(
        "clips-1000-by-600s.glb",
        tiny_with(|j, append| {
            let times = append(&f32s(&[0.0, 600.0]));
            let t = accessor(
                j,
                json!({"bufferView": times, "componentType": 5126, "count": 2, "type": "SCALAR",
                "min": [0.0], "max": [600.0]}),
            );
            let rot = append(&f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.38, 0.92]));
            let r = accessor(
                j,
                json!({"bufferView": rot, "componentType": 5126, "count": 2, "type": "VEC4"}),
            );
            let node = j["skins"][0]["joints"][1].clone();
            j["animations"] = (0..1000)
                .map(|k| {
                    json!({"name": format!("clip{k}"), "samplers": [{"input": t, "output": r}],
                    "channels": [{"sampler": 0, "target": {"node": node, "path": "rotation"}}]})
                })
                .collect();
        }),
        Expect::Error("--limit clips-seconds"),
    );
    c.add(
        "skins-16-by-1024-joints.glb",
        tiny_with(|j, _| {
            let first = j["nodes"].as_array().unwrap().len();
            let nodes = j["nodes"].as_array_mut().unwrap();
            let mut skins = Vec::new();
            for s in 0..16 {
                let start = nodes.len();
                for k in 0..1024 {
                    let mut n = json!({"name": format!("s{s}j{k}")});
                    if k + 1 < 1024 {
                        n["children"] = json!([start + k + 1]);
                    }
                    nodes.push(n);
                }
                skins.push(json!({"joints": (start..start + 1024).collect::<Vec<_>>()}));
            }
            let roots: Vec<usize> = (0..16).map(|s| first + s * 1024).collect();
            let tiny_skin = j["skins"][0].clone();
            let mut all = vec![tiny_skin];
            all.extend(skins);
            j["skins"] = Value::Array(all);
            let scene_nodes = j["scenes"][0]["nodes"].as_array_mut().unwrap();
            scene_nodes.extend(roots.into_iter().map(|r| json!(r)));
        }),
        Expect::Error("--limit joints"),
    );
    c.add(
        "jpeg-sof-after-70kb.glb",
        shared_texture(&jpeg_with_late_sof(20_000, 20_000, 70_000), "image/jpeg", 1),
        Expect::Error("--limit texture-side"),
    );
    c.add(
        "texture-shared-by-16.glb",
        shared_texture(&png(2048), "image/png", 16),
        Expect::Succeeds,
    );
    c.add_with(
        "texture-shared-by-16-limited.glb",
        shared_texture(&png(2048), "image/png", 16),
        &["--limit", "texture-mb=8"],
        Expect::Error("--limit texture-mb"),
    );
    c.add(
        "data-uri-image-too-wide.glb",
        tiny_with(|j, _| {
            let wide = image::RgbaImage::from_pixel(9000, 1, image::Rgba([1, 2, 3, 255]));
            let mut bytes = Vec::new();
            wide.write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::Png,
            )
            .unwrap();
            j["images"] = json!([{"uri": "data:image/png;base64,".to_string() + &base64(&bytes)}]);
            j["textures"] = json!([{"source": 0}]);
            j["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
        }),
        Expect::Error("--limit texture-side"),
    );

    // --- Files that are not regular files, or lie outside the model's folder.
    let external = |uri: &str| -> Vec<u8> {
        let base = tiny();
        let parsed = gltf::binary::Glb::from_slice(&base).unwrap();
        let mut j: Value = serde_json::from_slice(&parsed.json).unwrap();
        j["buffers"][0]["uri"] = json!(uri);
        serde_json::to_vec(&j).unwrap()
    };
    {
        let parsed = gltf::binary::Glb::from_slice(&tiny())
            .unwrap()
            .bin
            .unwrap()
            .into_owned();
        std::fs::write(dir.join("tiny.bin"), &parsed).unwrap();
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("outside.bin"), &parsed).unwrap();
        let fifo = dir.join("pipe.bin");
        let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(made.success());
        let _ = std::fs::remove_file(dir.join("sub/link.bin"));
        std::os::unix::fs::symlink(dir.join("outside.bin"), dir.join("sub/link.bin")).unwrap();
        let _ = std::fs::remove_file(dir.join("sub/inside-link.bin"));
        std::os::unix::fs::symlink("../sub/tiny.bin", dir.join("sub/inside-link.bin")).unwrap();
        std::fs::write(dir.join("sub/tiny.bin"), &parsed).unwrap();
    }
    c.add("external.gltf", external("tiny.bin"), Expect::Succeeds);
    c.add(
        "buffer-fifo.gltf",
        external("pipe.bin"),
        Expect::Error("not a regular file"),
    );
    c.add(
        "buffer-dev-zero.gltf",
        external("/dev/zero"),
        Expect::Error("outside"),
    );
    c.add(
        "buffer-etc-passwd.gltf",
        external("/etc/passwd"),
        Expect::Error("outside"),
    );
    c.add(
        "buffer-file-uri.gltf",
        external("file:///etc/passwd"),
        Expect::Error("outside"),
    );
    c.add(
        "sub/buffer-climbs.gltf",
        external("../outside.bin"),
        Expect::Error("outside"),
    );
    c.add(
        "sub/buffer-symlink-out.gltf",
        external("link.bin"),
        Expect::Error("outside"),
    );
    c.add(
        "sub/buffer-symlink-in.gltf",
        external("inside-link.bin"),
        Expect::Succeeds,
    );
    c.add_with(
        "sub/buffer-climbs-allowed.gltf",
        external("../outside.bin"),
        &["--allow-outside-files"],
        Expect::Succeeds,
    );
    c.add(
        "quantised-dev-zero.gltf",
        {
            let mut j: Value = serde_json::from_slice(&external("/dev/zero")).unwrap();
            j["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
            serde_json::to_vec(&j).unwrap()
        },
        Expect::Error("outside"),
    );
    c.add(
        "quantised-fifo.gltf",
        {
            let mut j: Value = serde_json::from_slice(&external("pipe.bin")).unwrap();
            j["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
            serde_json::to_vec(&j).unwrap()
        },
        Expect::Error("not a regular file"),
    );
    c.add(
        "quantised-no-required-list.glb",
        edit_glb(&tiny(), |j| {
            j["extensionsUsed"] = json!(["KHR_mesh_quantization"])
        }),
        Expect::Succeeds,
    );

    // --- Wrong values accepted before.
    {
        // A buffer file 3 bytes shorter than its byteLength (the reader pads to 4 bytes: the
        // padding must not make up for what is missing).
        let bin = std::fs::read(dir.join("tiny.bin")).unwrap();
        std::fs::write(dir.join("short.bin"), &bin[..bin.len() - 3]).unwrap();
    }
    c.add(
        "buffer-3-bytes-short.gltf",
        external("short.bin"),
        Expect::Error("truncated"),
    );
    c.add(
        "meshopt-200-views-of-one-stream.glb",
        meshopt_amplified(200, 1 << 21),
        Expect::Error("--limit decoded-mb"),
    );
    c.add(
        "texture-transform-nan.glb",
        tiny_with(|j, _| {
            j["images"] = json!([{"uri": "data:image/png;base64,".to_string() + &base64(&png(1))}]);
            j["textures"] = json!([{"source": 0}]);
            j["extensionsUsed"] = json!(["KHR_texture_transform"]);
            j["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
                "extensions": {"KHR_texture_transform": {"scale": [1e39, 1.0]}}}}}]);
        }),
        Expect::Error("KHR_texture_transform"),
    );
    c.add(
        "translation-key-1e30.glb",
        tiny_with(|j, append| {
            let times = append(&f32s(&[0.0, 1.0]));
            let t = accessor(
                j,
                json!({"bufferView": times, "componentType": 5126, "count": 2, "type": "SCALAR",
                "min": [0.0], "max": [1.0]}),
            );
            let tr = append(&f32s(&[0.0, 0.0, 0.0, 1e30, 0.0, 0.0]));
            let o = accessor(
                j,
                json!({"bufferView": tr, "componentType": 5126, "count": 2, "type": "VEC3"}),
            );
            let node = j["skins"][0]["joints"][1].clone();
            j["animations"] = json!([{"samplers": [{"input": t, "output": o}],
                "channels": [{"sampler": 0, "target": {"node": node, "path": "translation"}}]}]);
        }),
        Expect::Error("translation"),
    );
    c.add(
        "schema-error.glb",
        edit_glb(&tiny(), |j| {
            j["meshes"][0]["primitives"][0]["mode"] = json!("triangles")
        }),
        Expect::Error("invalid glTF"),
    );
    c.add(
        "indices-float.glb",
        tiny_with(|j, append| {
            let v = append(&f32s(&[0.0, 1.0, 3.0]));
            let a = accessor(
                j,
                json!({"bufferView": v, "componentType": 5126, "count": 3, "type": "SCALAR"}),
            );
            prim(j)["indices"] = json!(a);
        }),
        Expect::Error("not unsigned integers"),
    );
    c.add(
        "node-matrix-singular.glb",
        edit_glb(&tiny(), |j| {
            let n = j["skins"][0]["joints"][0].as_u64().unwrap() as usize;
            let node = j["nodes"][n].as_object_mut().unwrap();
            node.remove("translation");
            node.remove("rotation");
            node.remove("scale");
            node.insert(
                "matrix".into(),
                json!([
                    1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0
                ]),
            );
        }),
        Expect::Error("singular"),
    );

    // --- Found by the probe and not in the lists above.
    c.add(
        "meshes-5000-over-one-accessor.glb",
        edit_glb(&tiny(), |j| {
            // 5,000 meshes, each the tiny model's primitive over the same accessors, each on a
            // node of its own bound to the one skin.
            let p = prim(j).clone();
            let skin_node = j["nodes"]
                .as_array()
                .unwrap()
                .iter()
                .find(|n| n.get("skin").is_some())
                .unwrap()
                .clone();
            j["meshes"] = (0..5000).map(|_| json!({"primitives": [p]})).collect();
            let nodes = j["nodes"].as_array_mut().unwrap();
            let first = nodes.len();
            for k in 0..5000 {
                let mut n = skin_node.clone();
                n["mesh"] = json!(k);
                n["name"] = json!(format!("part{k}"));
                nodes.push(n);
            }
            let scene = j["scenes"][0]["nodes"].as_array_mut().unwrap();
            scene.extend((first..first + 5000).map(|n| json!(n)));
        }),
        Expect::Succeeds,
    );
    c.add(
        "texcoords-tiled-50.glb",
        textured_tiny(50.0),
        Expect::Succeeds,
    );
    c.add(
        "quantised-positions-small-scale.glb",
        quantised_tiny(),
        Expect::Succeeds,
    );
    c.add(
        "rotation-zero-quaternion.glb",
        edit_glb(&tiny(), |j| {
            let n = j["skins"][0]["joints"][1].as_u64().unwrap() as usize;
            j["nodes"][n]["rotation"] = json!([0.0, 0.0, 0.0, 0.0]);
        }),
        Expect::Error("rotation of length zero"),
    );
    c.add(
        "sparse-indices-with-stride.glb",
        {
            let sparse = tiny_with(|j, append| {
                let iv = append(&u32s(&[0, 0, 1, 0]));
                let vv = append(&f32s(&[0.0, 0.1, 0.0, 0.0, 0.2, 0.0]));
                let position = prim(j)["attributes"]["POSITION"].as_u64().unwrap() as usize;
                j["accessors"][position]["sparse"] = json!({"count": 2,
                    "indices": {"bufferView": iv, "componentType": 5125},
                    "values": {"bufferView": vv}});
            });
            // The indices' view strided, as the probe's file had it.
            edit_glb(&sparse, |j| {
                let position = prim(j)["attributes"]["POSITION"].as_u64().unwrap() as usize;
                let iv = j["accessors"][position]["sparse"]["indices"]["bufferView"].clone();
                j["bufferViews"][iv.as_u64().unwrap() as usize]["byteStride"] = json!(8);
            })
        },
        Expect::Error("byteStride"),
    );

    // --- Command-line values.
    for (name, args, problem) in [
        (
            "record-seconds-1e30",
            "record --seconds 1e30 --out x.mp4",
            "seconds",
        ),
        ("bench-warmup-1e30", "bench --warmup 1e30", "seconds"),
        ("bench-seconds-1e30", "bench --seconds 1e30", "seconds"),
        (
            "limit-file-mb-huge",
            "bake --limit file-mb=17592186044416 horse",
            "file-mb",
        ),
    ] {
        c.list.push(Case {
            name,
            file: PathBuf::new(),
            args: args.split(' ').map(str::to_string).collect(),
            expect: Expect::Refused(problem),
        });
    }
    c.list
}

/// The tiny model with `views` extra buffer views that all decode one compressed stream of
/// `count` 16-byte zeros (`EXT_meshopt_compression`): a few kilobytes that decode to
/// `views × count × 16` bytes.
fn meshopt_amplified(views: usize, count: usize) -> Vec<u8> {
    let zeros = vec![[0u32; 4]; count];
    let stream = meshopt::encode_vertex_buffer(&zeros).unwrap();
    let mut at = 0;
    let with_stream = tiny_with(|_, append| at = append(&stream));
    edit_glb(&with_stream, |j| {
        let offset = j["bufferViews"][at]["byteOffset"].clone();
        for _ in 0..views {
            j["bufferViews"].as_array_mut().unwrap().push(json!({
                "buffer": 0, "byteLength": count * 16, "byteStride": 16,
                "extensions": {"EXT_meshopt_compression": {"buffer": 0, "byteOffset": offset,
                    "byteLength": stream.len(), "byteStride": 16, "count": count,
                    "mode": "ATTRIBUTES"}}
            }));
        }
        j["extensionsUsed"] = json!(["EXT_meshopt_compression"]);
    })
}

/// The tiny model as gltfpack quantises a small model: positions as unsigned shorts on a grid
/// of 7.4 µm, the dequantising scale and offset folded into the inverse bind matrices (their
/// determinant about 4·10⁻¹⁶), with `KHR_mesh_quantization`.
fn quantised_tiny() -> Vec<u8> {
    let model = tiny_model();
    // A grid fine enough that the tiny model's 2 m need more than a short: shrink it to a
    // fifth (the skeleton with it), as a small prop would be.
    let shrink = 0.2f32;
    let step = 7.4e-6f32;
    let lo = model
        .mesh
        .positions
        .iter()
        .fold(glam::Vec3::splat(f32::MAX), |a, p| a.min(*p * shrink));
    let q: Vec<u8> = model
        .mesh
        .positions
        .iter()
        .flat_map(|p| {
            let g = ((*p * shrink - lo) / step).round();
            assert!(g.max_element() <= 65535.0, "{g}");
            [g.x as u16, g.y as u16, g.z as u16, 0]
        })
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let dequantise =
        glam::Mat4::from_translation(lo) * glam::Mat4::from_scale(glam::Vec3::splat(step));
    let quantised = tiny_with(move |j, append| {
        let v = append(&q);
        let a = accessor(
            j,
            json!({"bufferView": v, "componentType": 5123, "count": 10, "type": "VEC3",
                "min": [0, 0, 0], "max": [65535, 65535, 65535]}),
        );
        prim(j)["attributes"]["POSITION"] = json!(a);
        // Joint rest translations shrink with the mesh.
        for joint in j["skins"][0]["joints"].clone().as_array().unwrap() {
            let n = &mut j["nodes"][joint.as_u64().unwrap() as usize];
            if let Some(t) = n.get_mut("translation").and_then(|t| t.as_array_mut()) {
                for c in t.iter_mut() {
                    *c = json!(c.as_f64().unwrap() * shrink as f64);
                }
            }
        }
        let joints = j["skins"][0]["joints"].as_array().unwrap().len();
        // The tiny model's inverse bind matrices are translations by the joints' rest
        // heights (0 and 1 m): shrunk, then composed with the dequantisation.
        let ibms: Vec<f32> = (0..joints)
            .flat_map(|k| {
                let bind =
                    glam::Mat4::from_translation(glam::Vec3::new(0.0, k as f32 * shrink, 0.0));
                (bind.inverse() * dequantise).to_cols_array()
            })
            .collect();
        let m = append(&f32s(&ibms));
        let ma = accessor(
            j,
            json!({"bufferView": m, "componentType": 5126, "count": joints, "type": "MAT4"}),
        );
        j["skins"][0]["inverseBindMatrices"] = json!(ma);
        j["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
        j["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    });
    // Four shorts a position, the fourth padding, as gltfpack aligns them.
    edit_glb(&quantised, |j| {
        let a = prim(j)["attributes"]["POSITION"].as_u64().unwrap() as usize;
        let v = j["accessors"][a]["bufferView"].as_u64().unwrap() as usize;
        j["bufferViews"][v]["byteStride"] = json!(8);
    })
}

/// Standard base64, for `data:` URIs.
fn base64(bytes: &[u8]) -> String {
    use base64::Engine;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// Runs the command, killing it after `limit`; its exit code (None if killed) and stderr.
fn run_within(args: &[String], limit: Duration) -> (Option<i32>, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut stderr, &mut s).ok();
        s
    });
    let started = Instant::now();
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if started.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    (code, reader.join().unwrap_or_default())
}

#[test]
fn odd_and_hostile_files_are_refused_in_one_line_or_baked() {
    let tmp = tempfile::tempdir().unwrap();
    let keep = std::env::var_os("LODLAB_HARDENING_DIR").map(PathBuf::from);
    let dir = keep.as_deref().unwrap_or(tmp.path());
    std::fs::create_dir_all(dir).unwrap();
    let _ = std::fs::remove_file(dir.join("pipe.bin"));
    let cases = cases(dir);
    assert!(cases.len() >= 30, "{} cases", cases.len());
    if keep.is_some() {
        // One case a line: its name, then its arguments, tab-separated.
        let lines: Vec<String> = cases
            .iter()
            .map(|c| {
                std::iter::once(c.name.to_string())
                    .chain(c.args.iter().cloned())
                    .collect::<Vec<_>>()
                    .join("\t")
            })
            .collect();
        std::fs::write(dir.join("commands.txt"), lines.join("\n") + "\n").unwrap();
    }
    let mut failures = Vec::new();
    for case in &cases {
        let started = Instant::now();
        let (code, stderr) = run_within(&case.args, Duration::from_secs(60));
        let seconds = started.elapsed().as_secs_f32();
        let lines: Vec<&str> = stderr
            .lines()
            .filter(|l| !l.trim().is_empty() && !l.starts_with('[') && !l.contains(" WARN "))
            .collect();
        let shown = format!("error: {}: ", case.file.display());
        let verdict = match (&case.expect, code) {
            (_, None) => Some("killed after 60 s".to_string()),
            (Expect::Succeeds, Some(0)) => None,
            (Expect::Succeeds, c) => Some(format!("exit {c:?}: {stderr}")),
            (Expect::Error(problem), Some(1))
                if lines.len() == 1
                    && lines[0].starts_with(&shown)
                    && lines[0].contains(problem) =>
            {
                None
            }
            (Expect::Error(problem), c) => Some(format!(
                "wanted exit 1 and '{problem}', got exit {c:?}: {stderr}"
            )),
            (Expect::Refused(problem), Some(2)) if stderr.contains(problem) => None,
            (Expect::Refused(problem), c) => Some(format!(
                "wanted exit 2 and '{problem}', got exit {c:?}: {stderr}"
            )),
        };
        // Command-line cases name no file.
        let shown_file = match case.file.as_os_str().is_empty() {
            true => "\0".to_string(),
            false => case.file.display().to_string(),
        };
        eprintln!(
            "{:<40} {:>6.2} s  exit {:?}  {}",
            case.name,
            seconds,
            code,
            lines.first().map_or("", |l| l).replace(&shown_file, "FILE")
        );
        if let Some(v) = verdict {
            failures.push(format!("{}: {v}", case.name));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} failed: {failures:#?}",
        failures.len(),
        cases.len()
    );
}

/// A cache file that is a FIFO, a link to `/dev/zero` or 3 GiB long (a sparse file, more than
/// any cache file holds) is unusable, not read: the bake warns, bakes again, and leaves what is
/// there alone (it may be the user's).
#[test]
fn cache_files_that_are_not_regular_files_are_passed_over() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("tiny.glb");
    std::fs::write(&model, tiny()).unwrap();
    let cache = dir.path().join("cache");
    let args: Vec<String> = ["bake", "--methods", "rest-pose,as,as+is", "--cache"]
        .iter()
        .map(|s| s.to_string())
        .chain([cache.display().to_string(), model.display().to_string()])
        .collect();
    let (code, stderr) = run_within(&args, Duration::from_secs(120));
    assert_eq!(code, Some(0), "{stderr}");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "lods"))
        .collect();
    files.sort();
    assert!(files.len() >= 3, "{files:?}");
    std::fs::remove_file(&files[0]).unwrap();
    assert!(
        Command::new("mkfifo")
            .arg(&files[0])
            .status()
            .unwrap()
            .success()
    );
    std::fs::remove_file(&files[1]).unwrap();
    std::os::unix::fs::symlink("/dev/zero", &files[1]).unwrap();
    std::fs::File::options()
        .write(true)
        .open(&files[2])
        .unwrap()
        .set_len(3 << 30)
        .unwrap();
    let started = Instant::now();
    let (code, stderr) = run_within(&args, Duration::from_secs(120));
    assert_eq!(code, Some(0), "{stderr}");
    assert!(started.elapsed() < Duration::from_secs(110));
    for f in &files[..3] {
        let shown = f.display().to_string();
        assert!(
            stderr.contains(&shown),
            "no warning names {shown}: {stderr}"
        );
    }
    assert!(
        std::fs::symlink_metadata(&files[0])
            .unwrap()
            .file_type()
            .is_fifo()
    );
    assert!(
        std::fs::symlink_metadata(&files[1])
            .unwrap()
            .file_type()
            .is_symlink()
    );
    // The oversized one was a regular file in the cache: baked again in its place.
    assert!(std::fs::metadata(&files[2]).unwrap().len() < 1 << 20);
}

/// The valid but odd files, as a user meets them beyond `bake`: each renders
/// (`shot --method as+is`, its impostor made and placed) and exports levels that
/// glTF-Validator passes and that read back, each command within a minute. A mesh two nodes
/// draw in two places is drawn twice.
#[test]
fn odd_valid_files_render_and_export_valid_gltf() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let all = cases(dir);
    let odd = [
        "one-triangle-rigid.glb",
        "one-triangle-skinned.glb",
        "fan.glb",
        "fan-skinned.glb",
        "strip.glb",
        "unreferenced-vertices.glb",
        "shared-vertex-accessors.glb",
        "channel-without-node.glb",
        "mesh-on-two-nodes.glb",
        "texcoords-0-to-1000.glb",
        "inverse-bind-1e12.glb",
        "quantised-positions-small-scale.glb",
        "quantised-no-required-list.glb",
        "meshes-5000-over-one-accessor.glb",
    ];
    let cache = dir.join("cache").display().to_string();
    let mut failures = Vec::new();
    let mut exported = Vec::new();
    for name in odd {
        let case = all
            .iter()
            .find(|c| c.name == name)
            .unwrap_or_else(|| panic!("no case {name}"));
        assert!(matches!(case.expect, Expect::Succeeds), "{name}");
        let file = case.file.display().to_string();
        let png = dir.join(format!("{name}.png"));
        let out = dir.join(format!("{name}-export"));
        let commands: [Vec<String>; 2] = [
            [
                "shot", "--scene", "study", "--model", &file, "--count", "3", "--method", "as+is",
                "--size", "96x96", "--frames", "1", "--cache", &cache, "--out",
            ]
            .iter()
            .map(|s| s.to_string())
            .chain([png.display().to_string()])
            .collect(),
            ["export", "--model", &file, "--cache", &cache, "--out"]
                .iter()
                .map(|s| s.to_string())
                .chain([out.display().to_string()])
                .collect(),
        ];
        for args in &commands {
            let started = Instant::now();
            let (code, stderr) = run_within(args, Duration::from_secs(60));
            eprintln!(
                "{name:<40} {:<6} {:>6.2} s  exit {code:?}",
                args[0],
                started.elapsed().as_secs_f32()
            );
            if code != Some(0) {
                failures.push(format!("{name} {}: exit {code:?}: {stderr}", args[0]));
            }
        }
        if !png.is_file() {
            failures.push(format!("{name}: no picture"));
        }
        for entry in std::fs::read_dir(&out).into_iter().flatten() {
            let level = entry.unwrap().path();
            if level.extension().is_some_and(|e| e == "glb") {
                match lodlab::import::gltf::load(&level) {
                    Ok(m) if m.mesh.triangle_count() > 0 => {}
                    Ok(_) => failures.push(format!("{}: no triangles", level.display())),
                    Err(e) => {
                        failures.push(format!("{}: does not read back: {e}", level.display()))
                    }
                }
                exported.push(level);
            }
        }
    }
    // Two nodes drawing one mesh in two places: both copies are there.
    let two = dir.join("mesh-on-two-nodes.glb");
    assert_eq!(
        lodlab::import::gltf::load(&two)
            .unwrap()
            .mesh
            .triangle_count(),
        2
    );
    assert!(failures.is_empty(), "{failures:#?}");
    assert!(
        exported.len() >= odd.len() * 2,
        "{} files exported",
        exported.len()
    );
    if let Some(tools) = gltf_tools() {
        for (file, (errors, _, report)) in exported.iter().zip(validate(&tools, &exported)) {
            assert_eq!(errors, 0, "{}: {report}", file.display());
        }
    }
}
