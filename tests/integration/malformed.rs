//! A corpus of malformed glTF files, each made from the project's own tiny model by one
//! corruption of a kind found in the wild or by fuzzing: broken containers, buffers, views and
//! accessors that point outside their data, node graphs with cycles, animations and skins far
//! past what a character needs, non-finite numbers. Every file either loads (and then is the
//! model it claims to be) or fails with one line that names the file and its actual problem,
//! quickly, without a panic.
//!
//! `LODLAB_MALFORMED_DIR=DIR cargo test --test integration malformed` also leaves the files in DIR (the
//! fuzzer's seeds, or to try them on the command line).

/// The second round: valid but odd files, files that expand far past their size, pipes,
/// devices and files outside the model's folder, through `bake`, `shot` and `export`.
#[path = "malformed/second_round.rs"]
mod second_round;

use crate::common::{edit_glb, glb_of, tiny_model};
use image::ImageEncoder;
use lodlab::generate::glb::to_glb;
use lodlab::import::gltf::load;
use serde_json::{Value, json};
use std::path::Path;
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// What a file must give.
enum Expect {
    /// An error whose line contains this.
    Error(&'static str),
    /// A model with this many vertices.
    Loads(usize),
}

struct Case {
    name: &'static str,
    bytes: Vec<u8>,
    expect: Expect,
}

/// The accessor of attribute `semantic` of the first primitive.
fn attribute(j: &Value, semantic: &str) -> usize {
    j["meshes"][0]["primitives"][0]["attributes"][semantic]
        .as_u64()
        .unwrap() as usize
}

fn indices(j: &Value) -> usize {
    j["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap() as usize
}

fn view_of(j: &Value, accessor: usize) -> usize {
    j["accessors"][accessor]["bufferView"].as_u64().unwrap() as usize
}

/// The model's first animation sampler's input (key times) accessor.
fn key_times(j: &Value) -> usize {
    j["animations"][0]["samplers"][0]["input"].as_u64().unwrap() as usize
}

/// The joint nodes of the first skin.
fn joints(j: &Value) -> Vec<usize> {
    j["skins"][0]["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect()
}

/// Appends `data` to the binary chunk and returns a new buffer view over it.
fn append_view(glb: &[u8], data: &[u8]) -> (Vec<u8>, usize) {
    let parsed = gltf::binary::Glb::from_slice(glb).unwrap();
    let mut bin = parsed.bin.unwrap().into_owned();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let offset = bin.len();
    bin.extend_from_slice(data);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let mut json: Value = serde_json::from_slice(&parsed.json).unwrap();
    json["buffers"][0]["byteLength"] = json!(bin.len());
    let views = json["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": data.len()}));
    let view = views.len() - 1;
    let j = serde_json::to_vec(&json).unwrap();
    (glb_of(&j, Some(&bin)), view)
}

fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Every case, made from the tiny model (10 vertices, 2 joints, one clip).
fn corpus() -> Vec<Case> {
    let base = to_glb(&tiny_model());
    let edit = |f: &dyn Fn(&mut Value)| edit_glb(&base, f);
    let mut cases = Vec::new();
    let mut case = |name, bytes, expect| {
        cases.push(Case {
            name,
            bytes,
            expect,
        })
    };

    // The container.
    case("intact.glb", base.clone(), Expect::Loads(10));
    case(
        "truncated.glb",
        base[..base.len() / 2].to_vec(),
        Expect::Error("truncated or corrupt"),
    );
    case(
        "header-only.glb",
        base[..12].to_vec(),
        Expect::Error("truncated or corrupt"),
    );
    let mut b = base.clone();
    b[0..4].copy_from_slice(b"gLTF");
    case("bad-magic.glb", b, Expect::Error("not a glTF file"));
    let mut b = base.clone();
    b[8..12].copy_from_slice(&(base.len() as u32 + 4096).to_le_bytes());
    case(
        "header-length.glb",
        b,
        Expect::Error("truncated or corrupt"),
    );
    // The fuzzer's first find: a header length under the header's own 12 bytes overflowed a
    // subtraction in the gltf crate (a panic in debug builds).
    let mut b = b"glTF".to_vec();
    b.extend_from_slice(&2u32.to_le_bytes());
    b.extend_from_slice(&0u32.to_le_bytes());
    case(
        "header-length-zero.glb",
        b,
        Expect::Error("truncated or corrupt"),
    );
    let mut b = base.clone();
    b[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    case(
        "json-chunk-length.glb",
        b,
        Expect::Error("truncated or corrupt"),
    );
    let mut b = base.clone();
    b[4..8].copy_from_slice(&1u32.to_le_bytes());
    case("version-1.glb", b, Expect::Error("truncated or corrupt"));
    case(
        "json-syntax.gltf",
        br#"{"asset": {"version": "2.0"}, "nodes": [ {"mesh": 0} "#.to_vec(),
        Expect::Error("invalid JSON"),
    );
    case(
        "json-types.glb",
        edit(&|j| j["nodes"] = json!(5)),
        Expect::Error("glTF schema"),
    );
    case(
        "no-buffer-chunk.glb",
        {
            let parsed = gltf::binary::Glb::from_slice(&base).unwrap();
            glb_of(&parsed.json, None)
        },
        Expect::Error("binary chunk that is missing"),
    );

    // Buffers.
    case(
        "buffer-longer-than-chunk.glb",
        edit(&|j| {
            let n = j["buffers"][0]["byteLength"].as_u64().unwrap();
            j["buffers"][0]["byteLength"] = json!(n + 4096);
        }),
        Expect::Error("buffer 0"),
    );
    case(
        "buffer-uri-device.gltf",
        serde_json::to_vec(&json!({
            "asset": {"version": "2.0"},
            "buffers": [{"uri": "/dev/zero", "byteLength": 64}],
        }))
        .unwrap(),
        Expect::Error("refers to '/dev/zero', outside the model's folder"),
    );
    case(
        "buffer-uri-bad-base64.gltf",
        serde_json::to_vec(&json!({
            "asset": {"version": "2.0"},
            "buffers": [{"uri": "data:application/octet-stream;base64,@@@not base64@@@", "byteLength": 64}],
        }))
        .unwrap(),
        Expect::Error("base64"),
    );

    // Buffer views.
    case(
        "view-past-buffer.glb",
        edit(&|j| {
            let v = view_of(j, attribute(j, "POSITION"));
            j["bufferViews"][v]["byteOffset"] = json!(1 << 20);
        }),
        Expect::Error("buffer view"),
    );
    case(
        "view-length-past-buffer.glb",
        edit(&|j| {
            let v = view_of(j, attribute(j, "POSITION"));
            j["bufferViews"][v]["byteLength"] = json!(1 << 20);
        }),
        Expect::Error("buffer view"),
    );
    case(
        "stride-too-small-position.glb",
        edit(&|j| {
            let v = view_of(j, attribute(j, "POSITION"));
            j["bufferViews"][v]["byteStride"] = json!(4);
        }),
        Expect::Error("byteStride"),
    );
    case(
        "stride-too-small-weights.glb",
        edit(&|j| {
            let v = view_of(j, attribute(j, "WEIGHTS_0"));
            j["bufferViews"][v]["byteStride"] = json!(8);
        }),
        Expect::Error("byteStride"),
    );
    case(
        "stride-not-multiple-of-4.glb",
        edit(&|j| {
            let v = view_of(j, attribute(j, "POSITION"));
            j["bufferViews"][v]["byteStride"] = json!(13);
        }),
        Expect::Error("byteStride"),
    );

    // Accessors.
    case(
        "position-count-past-view.glb",
        edit(&|j| {
            let a = attribute(j, "POSITION");
            j["accessors"][a]["count"] = json!(100_000);
        }),
        Expect::Error("past the end of"),
    );
    case(
        "position-offset-past-view.glb",
        edit(&|j| {
            let a = attribute(j, "POSITION");
            j["accessors"][a]["byteOffset"] = json!(64);
        }),
        Expect::Error("past the end of"),
    );
    case(
        "position-offset-misaligned.glb",
        edit(&|j| {
            let a = attribute(j, "POSITION");
            j["accessors"][a]["byteOffset"] = json!(2);
        }),
        Expect::Error("aligned"),
    );
    case(
        "position-huge-count.glb",
        edit(&|j| {
            let a = attribute(j, "POSITION");
            j["accessors"][a]["count"] = json!(u32::MAX);
        }),
        Expect::Error("past the end of"),
    );
    case(
        "position-count-zero.glb",
        edit(&|j| {
            let a = attribute(j, "POSITION");
            j["accessors"][a]["count"] = json!(0);
        }),
        Expect::Error("count"),
    );
    case(
        "index-count-past-buffer.glb",
        edit(&|j| {
            let a = indices(j);
            j["accessors"][a]["count"] = json!(90_000);
        }),
        Expect::Error("past the end of"),
    );
    case(
        "index-out-of-range.glb",
        {
            let tris: Vec<u8> = [0u32, 1, 999]
                .iter()
                .flat_map(|i| i.to_le_bytes())
                .collect();
            let (b, view) = append_view(&base, &tris);
            edit_glb(&b, |j| {
                let a = indices(j);
                j["accessors"][a]["bufferView"] = json!(view);
                j["accessors"][a]["byteOffset"] = json!(0);
                j["accessors"][a]["count"] = json!(3);
                j["accessors"][a]["componentType"] = json!(5125);
            })
        },
        Expect::Error("999"),
    );
    case(
        "inverse-bind-past-buffer.glb",
        edit(&|j| {
            let a = j["skins"][0]["inverseBindMatrices"].as_u64().unwrap() as usize;
            j["accessors"][a]["count"] = json!(5000);
        }),
        Expect::Error("past the end of"),
    );
    case(
        "inverse-bind-too-few.glb",
        edit(&|j| {
            let a = j["skins"][0]["inverseBindMatrices"].as_u64().unwrap() as usize;
            j["accessors"][a]["count"] = json!(1);
        }),
        Expect::Error("inverse bind matrices"),
    );
    case(
        "sparse-indices-out-of-range.glb",
        {
            let (b, view) = append_view(&base, &[200u8, 0, 0, 0]);
            let values = append_view(&b, &f32_bytes(&[1.0, 2.0, 3.0]));
            edit_glb(&values.0, |j| {
                let a = attribute(j, "POSITION");
                j["accessors"][a]["sparse"] = json!({
                    "count": 1,
                    "indices": {"bufferView": view, "componentType": 5125},
                    "values": {"bufferView": values.1},
                });
            })
        },
        Expect::Error("sparse"),
    );
    case(
        "position-nan.glb",
        {
            let (b, view) = append_view(&base, &f32_bytes(&[f32::NAN; 30]));
            edit_glb(&b, |j| {
                let a = attribute(j, "POSITION");
                j["accessors"][a]["bufferView"] = json!(view);
                j["accessors"][a]["byteOffset"] = json!(0);
                j["accessors"][a]["min"] = json!([0.0, 0.0, 0.0]);
                j["accessors"][a]["max"] = json!([1.0, 1.0, 1.0]);
            })
        },
        Expect::Error("non-finite position"),
    );
    case(
        "weights-overflow.glb",
        {
            let w: Vec<f32> = (0..10).flat_map(|_| [3e38, 3e38, 0.0, 0.0]).collect();
            let (b, view) = append_view(&base, &f32_bytes(&w));
            edit_glb(&b, |j| {
                let a = attribute(j, "WEIGHTS_0");
                j["accessors"][a]["bufferView"] = json!(view);
                j["accessors"][a]["byteOffset"] = json!(0);
                j["accessors"][a]["componentType"] = json!(5126);
                j["accessors"][a]["normalized"] = json!(false);
            })
        },
        Expect::Loads(10),
    );
    case(
        "position-as-vec2.glb",
        edit(&|j| {
            let a = attribute(j, "POSITION");
            j["accessors"][a]["type"] = json!("VEC2");
        }),
        Expect::Error("POSITION is a Vec2 of F32"),
    );
    case(
        "indices-as-float.glb",
        edit(&|j| {
            let a = indices(j);
            j["accessors"][a]["componentType"] = json!(5126);
        }),
        Expect::Error("indices are Scalar of F32"),
    );

    // The node graph.
    case(
        "node-own-child.glb",
        edit(&|j| {
            let n = joints(j)[1];
            j["nodes"][n]["children"] = json!([n]);
        }),
        Expect::Error("is its own child"),
    );
    case(
        "node-cycle.glb",
        edit(&|j| {
            let [a, b] = joints(j)[..] else { panic!() };
            j["nodes"][b]["children"] = json!([a]);
        }),
        Expect::Error("cycle"),
    );
    case(
        "joint-ancestor-cycle.glb",
        edit(&|j| {
            let root = joints(j)[0];
            let nodes = j["nodes"].as_array_mut().unwrap();
            let (x, y) = (nodes.len(), nodes.len() + 1);
            nodes.push(json!({"name": "x", "children": [root, y]}));
            nodes.push(json!({"name": "y", "children": [x]}));
        }),
        Expect::Error("cycle"),
    );
    case(
        "node-two-parents.glb",
        edit(&|j| {
            let tip = joints(j)[1];
            let nodes = j["nodes"].as_array_mut().unwrap();
            nodes.push(json!({"name": "second parent", "children": [tip]}));
        }),
        Expect::Error("has two parents"),
    );
    case(
        "node-matrix-nan.glb",
        edit(&|j| {
            let n = joints(j)[0];
            let o = j["nodes"][n].as_object_mut().unwrap();
            for k in ["translation", "rotation", "scale"] {
                o.remove(k);
            }
            let mut m = vec![json!(0.0); 16];
            m[0] = json!(1.0);
            m[5] = json!(1.0);
            m[10] = json!(1.0);
            m[15] = json!(1.0);
            m[12] = json!(1e39);
            o.insert("matrix".into(), Value::Array(m));
        }),
        Expect::Error("non-finite"),
    );
    case(
        "deep-node-chain.glb",
        edit(&|j| chain_above_skeleton(j, 200_000)),
        Expect::Error("nodes; the limit is"),
    );
    // Under the node limit and under 1 MB: a 40,000-deep chain above the skeleton loads in
    // time linear in its depth.
    case(
        "deep-node-chain-under-the-limit.glb",
        edit(&|j| chain_above_skeleton(j, 40_000)),
        Expect::Loads(10),
    );
    case(
        "skin-joint-out-of-range.glb",
        edit(&|j| j["skins"][0]["joints"] = json!([0, 99_999])),
        Expect::Error("invalid glTF"),
    );
    case(
        "skin-many-joints.glb",
        edit(&|j| {
            let nodes = j["nodes"].as_array_mut().unwrap();
            let first = nodes.len();
            let extra = 5000;
            for k in 0..extra {
                nodes.push(json!({"name": format!("j{k}"), "translation": [0.0, 0.001, 0.0]}));
            }
            let mut js = joints(j);
            js.extend(first..first + extra);
            j["skins"][0]["joints"] = json!(js);
            j["skins"][0]
                .as_object_mut()
                .unwrap()
                .remove("inverseBindMatrices");
        }),
        Expect::Error("joints; the limit is"),
    );

    // Animations: the clip's key times replaced.
    let keys = |change: &dyn Fn(&mut Vec<f32>)| {
        let j = json_of(&base);
        let k = j["accessors"][key_times(&j)]["count"].as_u64().unwrap() as usize;
        let mut times: Vec<f32> = (0..k).map(|i| i as f32 / (k - 1) as f32).collect();
        change(&mut times);
        let (b, view) = append_view(&base, &f32_bytes(&times));
        edit_glb(&b, |j| {
            let a = key_times(j);
            let acc = j["accessors"][a].as_object_mut().unwrap();
            acc.insert("bufferView".into(), json!(view));
            acc.insert("byteOffset".into(), json!(0));
            acc.remove("min");
            acc.remove("max");
        })
    };
    case(
        "key-at-a-million-seconds.glb",
        keys(&|t| *t.last_mut().unwrap() = 1.0e6),
        Expect::Error("s long; the limit is 600 s"),
    );
    case(
        "key-times-nan.glb",
        keys(&|t| t[1] = f32::NAN),
        Expect::Error("key time"),
    );
    case(
        "key-times-decreasing.glb",
        keys(&|t| t[2] = -5.0),
        Expect::Error("key time"),
    );
    case(
        "sampler-output-too-short.glb",
        edit(&|j| {
            let out = j["animations"][0]["samplers"][0]["output"]
                .as_u64()
                .unwrap() as usize;
            j["accessors"][out]["count"] = json!(1);
        }),
        Expect::Error("output"),
    );
    case(
        "key-times-past-buffer.glb",
        edit(&|j| {
            let a = key_times(j);
            j["accessors"][a]["count"] = json!(1_000_000);
        }),
        Expect::Error("past the end of"),
    );

    // Materials and images.
    // Textured materials each take a texture layer: 301 are over the limit. (Plain colours
    // share one palette and load however many there are: tests/integration/field_models.rs.)
    case(
        "many-materials.glb",
        {
            let mut png = Vec::new();
            image::codecs::png::PngEncoder::new(&mut png)
                .write_image(&[200, 40, 40, 255], 1, 1, image::ExtendedColorType::Rgba8)
                .unwrap();
            let (b, view) = append_view(&base, &png);
            edit_glb(&b, |j| {
                j["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
                j["textures"] = json!([{"source": 0}]);
                j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
                let m = j["materials"][0].clone();
                let mats = j["materials"].as_array_mut().unwrap();
                for _ in 0..300 {
                    mats.push(m.clone());
                }
                let prim = j["meshes"][0]["primitives"][0].clone();
                let prims = j["meshes"][0]["primitives"].as_array_mut().unwrap();
                for k in 1..300 {
                    let mut p = prim.clone();
                    p["material"] = json!(k);
                    prims.push(p);
                }
            })
        },
        Expect::Error("textured materials; the limit is"),
    );
    case(
        "image-corrupt.glb",
        {
            let (b, view) = append_view(&base, b"\x89PNG\r\n\x1a\nthis is not the rest of a png");
            edit_glb(&b, |j| {
                j["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
                j["textures"] = json!([{"source": 0}]);
                j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
            })
        },
        Expect::Error("image 0"),
    );
    case(
        "image-huge-dimensions.glb",
        {
            let mut png = Vec::new();
            png.extend_from_slice(b"\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR");
            png.extend_from_slice(&100_000u32.to_be_bytes());
            png.extend_from_slice(&100_000u32.to_be_bytes());
            png.extend_from_slice(&[8, 6, 0, 0, 0]);
            let crc = crc32(&png[12..]);
            png.extend_from_slice(&crc.to_be_bytes());
            // An empty image data chunk and the end: a header the decoder reads in full.
            for chunk in [&b"IDAT"[..], &b"IEND"[..]] {
                png.extend_from_slice(&0u32.to_be_bytes());
                png.extend_from_slice(chunk);
                png.extend_from_slice(&crc32(chunk).to_be_bytes());
            }
            let (b, view) = append_view(&base, &png);
            edit_glb(&b, |j| {
                j["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
                j["textures"] = json!([{"source": 0}]);
                j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
            })
        },
        Expect::Error("image 0 is 100000×100000 texels; the limit is 8192"),
    );
    case(
        "texture-missing-image.glb",
        edit(&|j| {
            j["textures"] = json!([{"source": 7}]);
            j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
        }),
        Expect::Error("invalid glTF"),
    );
    cases
}

/// Puts a chain of `depth` nodes above the skeleton's root joint, the chain's top the scene's
/// only root.
fn chain_above_skeleton(j: &mut Value, depth: usize) {
    let root = joints(j)[0];
    let nodes = j["nodes"].as_array_mut().unwrap();
    let first = nodes.len();
    for k in 0..depth {
        let child = if k + 1 < depth { first + k + 1 } else { root };
        nodes.push(json!({"children": [child]}));
    }
    j["scenes"][0]["nodes"] = json!([first]);
}

/// The JSON chunk of a `.glb`.
fn json_of(glb: &[u8]) -> Value {
    serde_json::from_slice(&gltf::binary::Glb::from_slice(glb).unwrap().json).unwrap()
}

/// The PNG CRC-32 of `bytes`.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Loads `path` on a thread of its own, so that a hang reads as a failure instead of stalling
/// the test.
fn load_within(path: &Path, limit: Duration) -> Result<Result<usize, String>, String> {
    let (tx, rx) = mpsc::channel();
    let p = path.to_path_buf();
    std::thread::spawn(move || {
        let outcome = std::panic::catch_unwind(|| {
            load(&p)
                .map(|m| m.mesh.vertex_count())
                .map_err(|e| e.to_string())
        });
        let _ = tx.send(outcome.map_err(|_| "panicked".to_string()));
    });
    match rx.recv_timeout(limit) {
        Ok(outcome) => outcome,
        Err(_) => Err(format!("still loading after {limit:?}")),
    }
}

#[test]
fn every_malformed_file_is_refused_in_one_line_or_loads() {
    let cases = corpus();
    assert!(cases.len() >= 40, "{} cases", cases.len());
    let keep = std::env::var_os("LODLAB_MALFORMED_DIR");
    let dir = tempfile::tempdir().unwrap();
    let dir = keep.as_ref().map_or(dir.path(), Path::new);
    std::fs::create_dir_all(dir).unwrap();
    let mut failures = Vec::new();
    for case in &cases {
        let path = dir.join(case.name);
        std::fs::write(&path, &case.bytes).unwrap();
        let started = Instant::now();
        let outcome = load_within(&path, Duration::from_secs(30));
        let seconds = started.elapsed().as_secs_f32();
        let shown = path.display().to_string();
        let verdict = match (&outcome, &case.expect) {
            (Ok(Err(line)), Expect::Error(problem)) => {
                if !line.starts_with(&shown) || line.contains('\n') {
                    Some(format!("not one line naming the file: {line}"))
                } else if !line.contains(problem) {
                    Some(format!("wanted '{problem}': {line}"))
                } else {
                    None
                }
            }
            (Ok(Ok(n)), Expect::Loads(want)) if n == want => None,
            (Ok(Ok(n)), Expect::Loads(want)) => Some(format!("{n} vertices, wanted {want}")),
            (Ok(Ok(n)), Expect::Error(problem)) => {
                Some(format!("loaded ({n} vertices), wanted '{problem}'"))
            }
            (Ok(Err(line)), Expect::Loads(_)) => Some(format!("refused: {line}")),
            (Err(broke), _) => Some(broke.clone()),
        };
        eprintln!(
            "{:<36} {:>6.2} s  {}",
            case.name,
            seconds,
            match &outcome {
                Ok(Ok(n)) => format!("loads, {n} vertices"),
                Ok(Err(line)) => line.replace(&shown, "FILE"),
                Err(e) => e.clone(),
            }
        );
        if let Some(v) = verdict {
            failures.push(format!("{}: {v}", case.name));
        }
        if seconds > 10.0 {
            failures.push(format!("{}: took {seconds:.1} s", case.name));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The same corpus through the command line, as a user meets it: `lodlab bake FILE` exits
/// with 1 and one line naming the file and the problem, or bakes the file that loads.
#[test]
fn the_command_line_refuses_each_in_one_line_with_exit_code_1() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let mut failures = Vec::new();
    for case in corpus() {
        let path = dir.path().join(case.name);
        std::fs::write(&path, &case.bytes).unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_lodlab"))
            .args(["bake", "--first-error", "4", "--cache"])
            .arg(&cache)
            .arg(&path)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        let code = out.status.code();
        match case.expect {
            Expect::Error(problem) => {
                let named = format!("error: {}: ", path.display());
                let ok = code == Some(1)
                    && lines.len() == 1
                    && lines[0].starts_with(&named)
                    && lines[0].contains(problem);
                if !ok {
                    failures.push(format!("{}: exit {code:?}: {stderr}", case.name));
                }
            }
            Expect::Loads(_) => {
                if code != Some(0) {
                    failures.push(format!("{}: exit {code:?}: {stderr}", case.name));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Inputs on which the fuzzer (`fuzz/`) found the importer panicking, kept as found: each is
/// refused in one line. (A POSITION accessor index past the accessors, read by the gltf
/// crate's own validation; a channel animating an unknown property; an image in a buffer view
/// without a mimeType; translation keys stored as integers; see `validate.rs`.)
#[test]
fn the_fuzzers_crashers_are_refused_in_one_line() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-crashers");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        match load_within(&path, Duration::from_secs(30)) {
            Ok(Err(line)) => {
                assert!(line.starts_with(&path.display().to_string()), "{line}");
                assert!(!line.contains('\n'), "{line}");
                eprintln!("{line}");
            }
            Ok(Ok(n)) => eprintln!("{}: loads, {n} vertices", path.display()),
            Err(broke) => panic!("{}: {broke}", path.display()),
        }
        seen += 1;
    }
    assert!(seen >= 8, "{seen} crashers");
}
