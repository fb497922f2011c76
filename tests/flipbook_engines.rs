//! Flipbooks as the engines read them (issue 42): a candle in the wind (Perry's particle flame with
//! gusts) rendered at twice the sheet's rate; the even frames become a 4×4 flipbook written for each
//! engine convention, the odd frames are the true in-betweens. Each engine's own decode formula,
//! reimplemented here from its published source, blends frames t and t+1 along the decoded vectors;
//! the result must be closer (PSNR) to the true frame t+0.5 than a plain cross-fade, and the 16-bit
//! sheet's vectors must agree with pyrograph's optical flow within 1/4 pixel.
//! The six-way lighting sheets of a volume (issue 62) are tested in this binary too ([`sixway`]), and
//! a volume's flipbook whose motion comes from the simulation's velocity ([`volume_motion`]).

#[path = "engines/sixway.rs"]
mod sixway;
#[path = "engines/volume_motion.rs"]
mod volume_motion;

use std::path::Path;
use std::sync::Arc;

use pyrograph_frontend::core::{BuildOptions, Clip, CookCtx, Evaluator, Graph, GraphDoc, Image, PortType, Value};
use pyrograph_frontend::imaging::flipbook::optical_flow;

/// Sheet rows and columns: 16 frames in the sheet, 15 in-betweens to rebuild.
const SIDE: usize = 4;
/// Frame size.
const W: u32 = 96;
const H: u32 = 128;

/// One candle leaned by a breeze and shaken by gusts (the candle-in-wind preset's flame, framed
/// close), at twice the sheet's rate: the gusts scroll and the flame flickers per frame, so frame
/// 2k + 1 is the flame half-way between sheet frames k and k + 1.
const SCENE: &str = r#"(
    version: 3,
    nodes: {
        "root": (type: "particles.roots", params: {"layout": "row", "count": 1}),
        "wind": (type: "particles.wind_field", params: {"noise_c": 0.04, "k_p": 0.5, "k_s": 0.05, "height_unit": 0.1, "large_scale": "constant", "wind": (expr("1.0 * sin(time * 3.0 - 2.0)"), 0.0, 0.0), "seed": 5}),
        "flame": (type: "particles.particle_flame", params: {"frames": 32, "flicker": 0.2, "flicker_rate": 0.03, "seed": 1}),
        "render": (type: "particles.render_flames", params: {"width": 96, "height": 128, "camera_position": (0.4, 2.2, 10.0), "camera_target": (0.4, 2.2, 0.0)}),
    },
    edges: [("root.roots", "flame.roots"), ("wind.wind", "flame.wind"), ("flame.flames", "render.flames")],
)"#;

fn render() -> Vec<Arc<Image>> {
    let doc = GraphDoc::from_ron(SCENE).unwrap();
    let g = Graph::build(&doc, &pyrograph_frontend::registry(), Path::new("."), &BuildOptions::default()).unwrap();
    let ctx = CookCtx::new();
    let Value::Clip(clip) = Evaluator::new().output(&g, "render.image", &ctx).unwrap() else { panic!("render.image") };
    (0..clip.len()).map(|i| clip.image(i, &ctx).unwrap()).collect()
}

/// An RGBA image as premultiplied floats (what the engines blend).
fn premultiplied(img: &Image) -> Vec<[f32; 4]> {
    img.data().chunks_exact(4).map(|p| [p[0] * p[3], p[1] * p[3], p[2] * p[3], p[3]]).collect()
}

/// A texture as the GPU samples it: bilinear, texel centres at (k + 0.5) / size, addressed by
/// (u, v) with v pointing down the image (the file's rows); `wrap_u` repeats u, else it clamps.
struct Texture {
    w: usize,
    h: usize,
    px: Vec<[f32; 4]>,
    wrap_u: bool,
}

impl Texture {
    fn load(path: &Path, wrap_u: bool) -> Texture {
        let img = image::open(path).unwrap().into_rgba32f();
        let (w, h) = (img.width() as usize, img.height() as usize);
        Texture { w, h, px: img.pixels().map(|p| p.0).collect(), wrap_u }
    }

    fn sample(&self, u: f32, v: f32) -> [f32; 4] {
        let u = if self.wrap_u { u.rem_euclid(1.0) } else { u };
        let (x, y) = (u * self.w as f32 - 0.5, v * self.h as f32 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (tx, ty) = (x - x0, y - y0);
        let at = |dx: f32, dy: f32| {
            let xi = x0 as i64 + dx as i64;
            let xi = if self.wrap_u { xi.rem_euclid(self.w as i64) } else { xi.clamp(0, self.w as i64 - 1) };
            let yi = (y0 as i64 + dy as i64).clamp(0, self.h as i64 - 1);
            self.px[yi as usize * self.w + xi as usize]
        };
        let (a, b, c, d) = (at(0.0, 0.0), at(1.0, 0.0), at(0.0, 1.0), at(1.0, 1.0));
        std::array::from_fn(|k| (1.0 - tx) * (1.0 - ty) * a[k] + tx * (1.0 - ty) * b[k] + (1.0 - tx) * ty * c[k] + tx * ty * d[k])
    }
}

fn lerp(a: [f32; 4], b: [f32; 4], t: f32) -> [f32; 4] {
    std::array::from_fn(|k| a[k] + (b[k] - a[k]) * t)
}

/// How one engine rebuilds the frame between cells `k` and `k + 1` at `blend`, pixel (x, y) of
/// the particle quad; `with_motion` false gives the same engine's plain cross-fade.
type Blend = fn(&Texture, &Texture, f32, usize, f32, (f32, f32), bool) -> [f32; 4];

/// Unity VFX Graph, UV mode "Flipbook Motion Blend" (Unity-Technologies/Graphics,
/// com.unity.visualeffectgraph Shaders/VFXCommon.hlsl: GetSubUV, GetFlipbookMotionVectors and
/// SampleTexture(VFXSampler2D, VFXUVData); the output passes motionVectorScale * invFlipBookSize).
/// UVs have v up (Unity's texture origin is bottom-left).
fn unity(tex: &Texture, mv: &Texture, scale: f32, k: usize, blend: f32, uv: (f32, f32), with_motion: bool) -> [f32; 4] {
    let dim = (SIDE as f32, SIDE as f32);
    let sub_uv = |index: usize| {
        let tile = ((index % SIDE) as f32, dim.1 - 1.0 - (index / SIDE) as f32);
        ((tile.0 + uv.0) / dim.0, (tile.1 + uv.1) / dim.1)
    };
    // Unity's v is up; the file's rows run down.
    let fetch = |t: &Texture, (u, v): (f32, f32)| t.sample(u, 1.0 - v);
    let (a, b) = (sub_uv(k), sub_uv(k + 1));
    let varying = if with_motion { (scale / dim.0, scale / dim.1) } else { (0.0, 0.0) };
    let (ma, mb) = (fetch(mv, a), fetch(mv, b));
    let prev = ((ma[0] * 2.0 - 1.0) * -varying.0 * blend, (ma[1] * 2.0 - 1.0) * -varying.1 * blend);
    let next = ((mb[0] * 2.0 - 1.0) * varying.0 * (1.0 - blend), (mb[1] * 2.0 - 1.0) * varying.1 * (1.0 - blend));
    let s0 = fetch(tex, (a.0 + prev.0, a.1 + prev.1));
    let s1 = fetch(tex, (b.0 + next.0, b.1 + next.1));
    lerp(s0, s1, blend)
}

/// Unreal frame blending with motion vectors (the material of Klemen Lozar's "Frame Blending with
/// Motion Vectors", 2015, built in UE4's material editor: SubUV UVs with v down, the vector
/// decoded by ConstantBiasScale(bias −0.5, scale 2), times the strength, frame A's UV moved back
/// by it × phase and frame B's forward by it × (1 − phase), then a lerp by phase).
fn unreal(tex: &Texture, mv: &Texture, strength: f32, k: usize, phase: f32, uv: (f32, f32), with_motion: bool) -> [f32; 4] {
    let sub_uv = |index: usize| (((index % SIDE) as f32 + uv.0) / SIDE as f32, ((index / SIDE) as f32 + uv.1) / SIDE as f32);
    let (a, b) = (sub_uv(k), sub_uv(k + 1));
    let s = if with_motion { strength } else { 0.0 };
    let decode = |p: [f32; 4]| ((p[0] - 0.5) * 2.0 * s, (p[1] - 0.5) * 2.0 * s);
    let (ma, mb) = (decode(mv.sample(a.0, a.1)), decode(mv.sample(b.0, b.1)));
    let s0 = tex.sample(a.0 - ma.0 * phase, a.1 - ma.1 * phase);
    let s1 = tex.sample(b.0 + mb.0 * (1.0 - phase), b.1 + mb.1 * (1.0 - phase));
    lerp(s0, s1, phase)
}

/// SideFX Labs' motion-vector shader (SideFX GameDevelopmentToolset, Unity shader
/// "sidefx/MotionVector", GetMotionVectorDisplacedTexture, single motion vector): UVs flipped to v
/// down for the cell arithmetic (the column wraps through the texture's repeat addressing) and back,
/// G flipped, (rg − 0.5) · 2 / (cols, rows) · Distortion added to frame A's UV × phase and taken
/// from frame B's × (1 − phase), then a lerp by phase. Its row index divides by rows where the
/// column count is meant, so it is only right for square sheets, as this one is.
fn labs(tex: &Texture, mv: &Texture, distortion: f32, k: usize, phase: f32, uv: (f32, f32), with_motion: bool) -> [f32; 4] {
    let (cols, rows) = (SIDE as f32, SIDE as f32);
    let orig = (uv.0, 1.0 - uv.1);
    let custom = |f: f32| {
        let c = (f / cols + orig.0 / cols, (f / rows).floor() / rows + orig.1 / rows);
        (c.0, 1.0 - c.1)
    };
    let fetch = |t: &Texture, (u, v): (f32, f32)| t.sample(u, 1.0 - v);
    let (a, b) = (custom(k as f32), custom(k as f32 + 1.0));
    let m = fetch(mv, a);
    let d = if with_motion { distortion } else { 0.0 };
    let intens = ((m[0] - 0.5) * 2.0 / cols * d, ((1.0 - m[1]) - 0.5) * 2.0 / rows * d);
    let fwd = (a.0 + phase * intens.0, a.1 + phase * intens.1);
    let rev = (b.0 - (1.0 - phase) * intens.0, b.1 - (1.0 - phase) * intens.1);
    lerp(fetch(tex, fwd), fetch(tex, rev), phase)
}

fn psnr(a: &[[f32; 4]], b: &[[f32; 4]]) -> f64 {
    let mse = a.iter().zip(b).flat_map(|(p, q)| (0..4).map(move |k| f64::from(p[k] - q[k]).powi(2))).sum::<f64>()
        / (a.len() * 4) as f64;
    10.0 * (1.0 / mse.max(1e-12)).log10()
}

/// Cooks imaging.write_flipbook on `frames` (at 24 fps) with `params` set.
fn cook_writer(frames: &[Arc<Image>], params: &[(&str, Value)]) {
    let reg = pyrograph_frontend::registry();
    let node = reg.get("imaging.write_flipbook").unwrap();
    let clip = Clip::from_frames(PortType::Image, 24.0, frames.iter().cloned().map(Value::Image).collect());
    let mut set = vec![("clip", Value::Clip(clip))];
    set.extend(params.iter().map(|(name, v)| (*name, v.clone())));
    pyrograph_frontend::core::testing::cook_node(&**node, &set).unwrap();
}

/// Writes the flipbook of `frames` for `convention` into `dir` and returns the side-car.
fn write_flipbook(frames: &[Arc<Image>], convention: &str, dir: &Path) -> serde_json::Value {
    let side = Value::Int(SIDE as i64);
    cook_writer(
        frames,
        &[
            ("rows", side.clone()),
            ("cols", side),
            ("alpha", Value::Enum("premultiplied".into())),
            ("convention", Value::Enum(convention.into())),
            ("path", Value::Path(dir.join("fire.png"))),
        ],
    );
    serde_json::from_str(&std::fs::read_to_string(dir.join(format!("fire_{SIDE}x{SIDE}.json"))).unwrap()).unwrap()
}

/// A blob drifting right and wobbling, 32 frames of 48×64 8-bit RGBA PNG in `dir` (integer
/// arithmetic after one rounding, so every machine writes the same bytes).
fn drifting_blob(dir: &Path) {
    for k in 0..32u32 {
        let (cx, cy) = (14.0 + 0.6 * f64::from(k), 36.0 + 3.0 * (f64::from(k) * 0.4).sin());
        let img = image::RgbaImage::from_fn(48, 64, |x, y| {
            let d2 = ((f64::from(x) - cx).powi(2) + (f64::from(y) - cy).powi(2) * 0.5) / 40.0;
            let a = (255.0 * (-d2).exp()).round() as u8;
            image::Rgba([255, 40 + (x * 3) as u8, (y * 2) as u8, a])
        });
        img.save(dir.join(format!("f_{k:04}.png"))).unwrap();
    }
}

/// The generic flipbook (the default) is what it was before the engine conventions, byte for byte:
/// the SHA-256 of the files the previous stop's release binary wrote from the same frames and
/// graph, plain and with padding, a power-of-two sheet, premultiplied alpha and a set motion range.
#[test]
fn the_generic_flipbook_is_byte_identical_to_before() {
    use sha2::Digest;
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    drifting_blob(&frames);
    let text = GENERIC.replace("FRAMES", &frames.display().to_string()).replace("OUT", &dir.path().display().to_string());
    let g =
        Graph::build(&GraphDoc::from_ron(&text).unwrap(), &pyrograph_frontend::registry(), dir.path(), &BuildOptions::default())
            .unwrap();
    let (mut ev, ctx) = (Evaluator::new(), CookCtx::new());
    for port in ["a.path", "b.path"] {
        ev.output(&g, port, &ctx).unwrap();
    }
    let before = [
        ("a/fire_4x8.json", "6d3a45f06f60ac4981531bec28930d6a45979fb5947b90579384d217a0ee6caa"),
        ("a/fire_4x8.png", "81cc938697865f72385d071b77f4af4e40e01f444aab79492be371d105ac173f"),
        ("a/fire_4x8_mv.png", "813dff0c2ee0da2f7fd7aa7b12c5f9ddb498a55802901c49f3e5ced4594dbbac"),
        ("b/fire_4x8.json", "63a7d9d3a4c96498f812d88189954d2eb40aca2540a9b6948991a704fd7187af"),
        ("b/fire_4x8.png", "46a414b586c969a3e93b51137ad6c1d0c3fcea69ed64345cdea2608d75faadd1"),
        ("b/fire_4x8_mv.png", "1da1f007c007a9e9d79ca1f385c57aa2dd3b6f32abaa371e58dce519fcc155ad"),
    ];
    for (file, hash) in before {
        let bytes = std::fs::read(dir.path().join(file)).unwrap();
        let now: String = sha2::Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(now, hash, "{file} changed");
    }
}

/// The graph of that test: FRAMES and OUT are replaced by folders.
const GENERIC: &str = r#"(
    version: 3,
    nodes: {
        "frames": (type: "imaging.load_sequence", params: {"path": "FRAMES"}),
        "a": (type: "imaging.write_flipbook", params: {"path": "OUT/a/fire.png", "rows": 4, "cols": 8}),
        "b": (type: "imaging.write_flipbook", params: {"path": "OUT/b/fire.png", "rows": 4, "cols": 8, "padding": 3, "power_of_two": true, "alpha": "premultiplied", "motion_range": 2.5}),
    },
    edges: [("frames.clip", "a.clip"), ("frames.clip", "b.clip")],
)"#;

/// The engine's frame half-way between cells `k` and `k + 1`, over the whole particle quad (with
/// motion, or as the same engine's cross-fade).
fn in_between(blend: Blend, tex: &Texture, mv: &Texture, scale: f32, k: usize, motion: bool) -> Vec<[f32; 4]> {
    (0..(W * H) as usize)
        .map(|i| {
            let (x, y) = ((i % W as usize) as f32 + 0.5, (i / W as usize) as f32 + 0.5);
            // The quad's uv: u right, v up (Unity and the Labs shader take it so; Unreal's v down
            // is its own SubUV arithmetic's business, handled by `unreal_uv`).
            blend(tex, mv, scale, k, 0.5, (x / W as f32, 1.0 - y / H as f32), motion)
        })
        .collect()
}

/// Mean PSNR of the engine's in-betweens (with motion, and as a cross-fade) against the truth.
fn rebuild(blend: Blend, tex: &Texture, mv: &Texture, scale: f32, truth: &[Arc<Image>]) -> (f64, f64) {
    let (mut with, mut without) = (0.0, 0.0);
    for (k, t) in truth.iter().enumerate() {
        let expected = premultiplied(t);
        with += psnr(&in_between(blend, tex, mv, scale, k, true), &expected);
        without += psnr(&in_between(blend, tex, mv, scale, k, false), &expected);
    }
    (with / truth.len() as f64, without / truth.len() as f64)
}

#[test]
fn every_engine_rebuilds_the_in_between_frames_better_than_a_cross_fade() {
    let all = render();
    assert_eq!(all.len(), 2 * SIDE * SIDE);
    let sheet_frames: Vec<Arc<Image>> = all.iter().step_by(2).cloned().collect();
    let truth: Vec<Arc<Image>> = all.iter().skip(1).step_by(2).take(SIDE * SIDE - 1).cloned().collect();
    let engines: [(&str, Blend, &str, bool); 3] = [
        ("unity", unity, "Motion Vector Scale", false),
        ("unreal", unreal_uv, "Motion Vector Strength", false),
        ("houdini-labs", labs, "Distortion", true),
    ];
    for (name, blend, setting, wrap) in engines {
        let dir = tempfile::tempdir().unwrap();
        let json = write_flipbook(&sheet_frames, name, dir.path());
        assert_eq!(json["engine_setting"], setting, "{json}");
        assert_eq!(json["motion_bits"], 16);
        let scale = json["engine_value"].as_f64().unwrap() as f32;
        let tex = Texture::load(&dir.path().join(format!("fire_{SIDE}x{SIDE}.png")), wrap);
        let mv_path = dir.path().join(format!("fire_{SIDE}x{SIDE}_mv.png"));
        assert_eq!(image::open(&mv_path).unwrap().color(), image::ColorType::Rgba16, "{name}: a 16-bit motion sheet");
        let mv = Texture::load(&mv_path, wrap);
        let (with, without) = rebuild(blend, &tex, &mv, scale, &truth);
        println!("{name}: {setting} {scale}; in-betweens {with:.2} dB with motion, {without:.2} dB cross-faded");
        assert!(with > without + 1.0, "{name}: {with:.2} dB with motion vs {without:.2} dB cross-faded");
        check_vectors(name, &mv, scale, &sheet_frames);
        if name == "unity" && std::env::var_os("REGENERATE").is_some() {
            picture(dir.path(), &tex, &mv, scale, &sheet_frames, &truth);
        }
    }
}

/// With REGENERATE=1: the guide book's pictures (the Unity sheets, and the in-between where the flame
/// moves most: frames t and t+1, their cross-fade, Unity's motion blend and the true frame t+0.5,
/// 2× in size; under the blends, their difference from the truth × 8).
fn picture(dir: &Path, tex: &Texture, mv: &Texture, scale: f32, frames: &[Arc<Image>], truth: &[Arc<Image>]) {
    let images = pyrograph_testing::workspace().join("docs/images");
    for (from, to) in [("fire_4x4.png", "flipbook-unity_4x4.png"), ("fire_4x4_mv.png", "flipbook-unity_4x4_mv.png")] {
        std::fs::copy(dir.join(from), images.join(to)).unwrap();
    }
    let k = (0..truth.len())
        .max_by(|&a, &b| {
            let d = |k: usize| -psnr(&premultiplied(&frames[k]), &premultiplied(&frames[k + 1]));
            d(a).total_cmp(&d(b))
        })
        .unwrap();
    let exact = premultiplied(&truth[k]);
    let (fade, blend) = (in_between(unity, tex, mv, scale, k, false), in_between(unity, tex, mv, scale, k, true));
    let diff = |a: &[[f32; 4]]| -> Vec<[f32; 4]> {
        a.iter().zip(&exact).map(|(p, q)| std::array::from_fn(|c| if c == 3 { 1.0 } else { 8.0 * (p[c] - q[c]).abs() })).collect()
    };
    let blank = vec![[0.0; 4]; (W * H) as usize];
    let rows = [
        [premultiplied(&frames[k]), premultiplied(&frames[k + 1]), fade.clone(), blend.clone(), exact.clone()],
        [blank.clone(), blank.clone(), diff(&fade), diff(&blend), blank],
    ];
    let (pw, ph, gap) = (2 * W, 2 * H, 4);
    let mut out = image::RgbImage::from_pixel(5 * pw + 4 * gap, 2 * ph + gap, image::Rgb([40, 40, 40]));
    for (r, row) in rows.iter().enumerate() {
        for (n, panel) in row.iter().enumerate() {
            for y in 0..ph {
                for x in 0..pw {
                    let p = panel[((y / 2) * W + x / 2) as usize];
                    let c = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
                    out.put_pixel(n as u32 * (pw + gap) + x, r as u32 * (ph + gap) + y, image::Rgb([c(p[0]), c(p[1]), c(p[2])]));
                }
            }
        }
    }
    out.save(images.join("flipbook-inbetween.png")).unwrap();
    println!("picture: in-between {k}");
}

/// `unreal` takes the quad's v down: the quad's uv as the other engines get it, flipped.
fn unreal_uv(tex: &Texture, mv: &Texture, s: f32, k: usize, phase: f32, uv: (f32, f32), m: bool) -> [f32; 4] {
    unreal(tex, mv, s, k, phase, (uv.0, 1.0 - uv.1), m)
}

/// The 16-bit sheet's vectors, decoded with each engine's formula and turned back into frame
/// pixels (x right, y down), against pyrograph's optical flow from each frame to the next.
fn check_vectors(name: &str, mv: &Texture, scale: f32, frames: &[Arc<Image>]) {
    let (w, h) = (W as usize, H as usize);
    let mut worst = 0.0f32;
    // Interior frames: Unity and Unreal cells hold the velocity at the frame (the mean of the motion
    // to the next frame and of minus the motion back to the previous one), the Labs cells the
    // motion to the next frame.
    for k in 1..frames.len() - 1 {
        let (mut u, mut v) = optical_flow(&frames[k], &frames[k + 1]);
        if name != "houdini-labs" {
            let (bu, bv) = optical_flow(&frames[k], &frames[k - 1]);
            u.data.iter_mut().zip(&bu.data).for_each(|(f, b)| *f = 0.5 * (*f - b));
            v.data.iter_mut().zip(&bv.data).for_each(|(f, b)| *f = 0.5 * (*f - b));
        }
        let (cx, cy) = ((k % SIDE) * w, (k / SIDE) * h);
        for y in 0..h {
            for x in 0..w {
                let p = mv.px[(cy + y) * mv.w + cx + x];
                let (r, g) = (p[0], p[1]);
                let (dx, dy) = match name {
                    // Cell UVs, v up.
                    "unity" => ((r * 2.0 - 1.0) * scale * w as f32, -(g * 2.0 - 1.0) * scale * h as f32),
                    // Sheet UVs, v down.
                    "unreal" => ((r - 0.5) * 2.0 * scale * mv.w as f32, (g - 0.5) * 2.0 * scale * mv.h as f32),
                    // Cell UVs, G flipped, against the motion.
                    _ => (-(r - 0.5) * 2.0 * scale * w as f32, (0.5 - g) * 2.0 * scale * h as f32),
                };
                let i = y * w + x;
                worst = worst.max((dx - u.data[i]).abs()).max((dy - v.data[i]).abs());
            }
        }
    }
    println!("{name}: largest difference from the optical flow {worst:.4} px");
    assert!(worst <= 0.25, "{name}: decoded vectors differ from the flow by {worst} px");
}
