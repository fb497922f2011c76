//! Tests of the flipbook layout, motion sheet, optical flow and writer.

use super::*;
use pyrograph_core::{PortType, Value};

fn numbered(n: usize, w: u32, h: u32) -> Vec<Arc<Image>> {
    (0..n)
        .map(|k| {
            let v = k as f32 / n as f32;
            Arc::new(Image::from_vec(w, h, Channels::Rgba, (0..w * h).flat_map(|_| [v, 0.0, 0.0, 0.5]).collect()).unwrap())
        })
        .collect()
}

#[test]
fn cells_run_left_to_right_then_top_to_bottom() {
    assert_eq!(cell_origin(0, 3, (10, 20)), (0, 0));
    assert_eq!(cell_origin(2, 3, (10, 20)), (20, 0));
    assert_eq!(cell_origin(3, 3, (10, 20)), (0, 20));
    let frames = numbered(6, 4, 2);
    let opts = FlipbookOptions { rows: 2, cols: 3, padding: 1, ..Default::default() };
    let fb = build_flipbook(&frames, &opts).unwrap();
    assert_eq!(fb.sheet.size(), (18, 8));
    assert_eq!(fb.cell, (6, 4));
    for k in 0..6 {
        let (ox, oy) = cell_origin(k, 3, fb.cell);
        // Padding is transparent, the frame starts one pixel in.
        assert_eq!(fb.sheet.pixel(ox, oy)[3], 0.0);
        let p = fb.sheet.pixel(ox + 1, oy + 1);
        assert!((p[0] - k as f32 / 6.0).abs() < 1e-6 && p[3] == 0.5, "cell {k}: {p:?}");
    }
    // Constant frames do not move: every motion pixel is 0.5.
    assert!(fb.motion.data().chunks(4).all(|p| p[0] == 0.5 && p[1] == 0.5));
}

#[test]
fn premultiplied_sheets_multiply_colour_by_alpha() {
    let frames = numbered(4, 2, 2);
    let opts = FlipbookOptions { rows: 2, cols: 2, alpha: AlphaMode::Premultiplied, ..Default::default() };
    let fb = build_flipbook(&frames, &opts).unwrap();
    // Cell 3 (bottom right) holds red 0.75 with alpha 0.5.
    let p = fb.sheet.pixel(2, 2);
    assert!((p[0] - 0.75 * 0.5).abs() < 1e-6 && p[3] == 0.5, "{p:?}");
}

#[test]
fn cell_count_must_match_the_frames() {
    let frames = numbered(6, 2, 2);
    let more = build_flipbook(&frames, &FlipbookOptions { rows: 3, cols: 3, ..Default::default() }).unwrap_err().to_string();
    assert!(more.contains("9 cells but the clip has only 6 frames"), "{more}");
    let fewer = build_flipbook(&frames, &FlipbookOptions { rows: 1, cols: 4, ..Default::default() }).unwrap_err().to_string();
    assert!(fewer.contains("cannot hold the clip's 6 frames"), "{fewer}");
    assert!(check_cells(6, 0, 6).is_err());
}

#[test]
fn power_of_two_and_file_names() {
    assert_eq!(nearest_power_of_two(2400), 2048);
    assert_eq!(nearest_power_of_two(3100), 4096);
    assert_eq!(nearest_power_of_two(1), 1);
    let frames = numbered(4, 30, 30);
    let fb = build_flipbook(&frames, &FlipbookOptions { rows: 2, cols: 2, power_of_two: true, ..Default::default() }).unwrap();
    assert_eq!(fb.sheet.size(), (64, 64));
    assert_eq!(fb.frame, (32, 32));
    assert_eq!(sheet_path(Path::new("out/fire.png"), 8, 8, "", "png"), PathBuf::from("out/fire_8x8.png"));
    assert_eq!(sheet_path(Path::new("fire.png"), 4, 6, "_mv", "png"), PathBuf::from("fire_4x6_mv.png"));
    let about = Sidecar { frames: 4, fps: 24.0, sheet: "f_2x2.png", motion: None, motion_bits: 8 };
    let json = sidecar_json(&fb, &FlipbookOptions { rows: 2, cols: 2, ..Default::default() }, &about);
    assert!(!json.contains("convention") && !json.contains("mip_levels"), "{json}");
    for key in ["\"rows\": 2", "\"cols\": 2", "\"frames\": 4", "\"fps\": 24", "\"alpha\": \"straight\"", "\"motion_range_px\""] {
        assert!(json.contains(key), "{key} missing in {json}");
    }
}

/// A smooth texture translated by (dx, dy).
fn texture(w: u32, h: u32, dx: f32, dy: f32) -> Image {
    Image::gray_from_fn(w, h, |x, y| {
        let (x, y) = (x as f32 - dx, y as f32 - dy);
        0.5 + 0.2 * (x * 0.21).sin() * (y * 0.17).cos() + 0.15 * (x * 0.07 + y * 0.11).sin() + 0.1 * (y * 0.29 - x * 0.05).cos()
    })
}

fn median(mut v: Vec<f32>) -> f32 {
    v.sort_by(f32::total_cmp);
    v[v.len() / 2]
}

#[test]
fn flow_of_a_translated_pattern_points_the_right_way() {
    for (dx, dy) in [(3.0f32, -2.0f32), (-1.5, 4.0), (0.0, 0.0)] {
        let (a, b) = (texture(96, 80, 0.0, 0.0), texture(96, 80, dx, dy));
        let (u, v) = optical_flow(&a, &b);
        let inner = |p: &Plane| -> Vec<f32> {
            (0..p.data.len())
                .filter(|k| (12..84).contains(&(k % 96)) && (12..68).contains(&(k / 96)))
                .map(|k| p.data[k])
                .collect()
        };
        let (mu, mv) = (median(inner(&u)), median(inner(&v)));
        assert!((mu - dx).abs() < 0.2 && (mv - dy).abs() < 0.2, "shift ({dx}, {dy}): median flow ({mu}, {mv})");
    }
}

#[test]
fn an_empty_background_does_not_move() {
    let blob =
        |cx: f32| Image::gray_from_fn(64, 64, |x, y| (-((x as f32 - cx).powi(2) + (y as f32 - 32.0).powi(2)) / 18.0).exp());
    let (u, v) = optical_flow(&blob(30.0), &blob(32.0));
    // Far from the blob: exactly zero; at the blob's flank: about +2 px in x.
    assert_eq!((u.data[5 * 64 + 5], v.data[5 * 64 + 5]), (0.0, 0.0));
    assert!((u.data[32 * 64 + 27] - 2.0).abs() < 0.5, "{}", u.data[32 * 64 + 27]);
}

#[test]
fn motion_sheet_encodes_around_one_half() {
    let frames: Vec<Arc<Image>> = (0..4).map(|k| Arc::new(texture(64, 64, 2.0 * k as f32, 0.0))).collect();
    let fb = build_flipbook(&frames, &FlipbookOptions { rows: 2, cols: 2, motion_range: 4.0, ..Default::default() }).unwrap();
    // 2 px right with range 4: R ≈ 0.5 + 2/8 = 0.75, G ≈ 0.5, in the middle of every cell (also the last).
    for k in 0..4 {
        let (ox, oy) = cell_origin(k, 2, fb.cell);
        let p = fb.motion.pixel(ox + 32, oy + 32);
        assert!((p[0] - 0.75).abs() < 0.03 && (p[1] - 0.5).abs() < 0.03, "cell {k}: {p:?}");
    }
    assert_eq!(fb.motion_range, 4.0);
}

#[test]
fn mismatched_frame_sizes_are_errors() {
    let mut frames = numbered(2, 4, 4);
    frames.push(Arc::new(Image::new(3, 3, Channels::Rgba)));
    frames.push(Arc::new(Image::new(4, 4, Channels::Rgba)));
    let e = build_flipbook(&frames, &FlipbookOptions { rows: 2, cols: 2, ..Default::default() }).unwrap_err().to_string();
    assert!(e.contains("frame 2 is 3x3"), "{e}");
}

#[test]
fn writer_puts_rxc_into_the_names_and_writes_a_sidecar() {
    let dir = tempfile::tempdir().unwrap();
    let reg = {
        let mut r = pyrograph_core::Registry::new();
        crate::register(&mut r);
        r
    };
    let node = reg.get("imaging.write_flipbook").unwrap();

    let frames: Vec<Value> = numbered(4, 4, 4).into_iter().map(Value::Image).collect();
    let clip = pyrograph_core::Clip::from_frames(PortType::Image, 12.0, frames);
    let set = [
        ("clip", Value::Clip(clip)),
        ("rows", Value::Int(2)),
        ("cols", Value::Int(2)),
        ("path", Value::Path(dir.path().join("fire.png"))),
    ];
    let out = pyrograph_core::testing::cook_node(&**node, &set).unwrap();
    assert!(matches!(&out[0], Value::Path(p) if p.ends_with("fire_2x2.png")));
    assert!(dir.path().join("fire_2x2_mv.png").exists());
    let json = std::fs::read_to_string(dir.path().join("fire_2x2.json")).unwrap();
    assert!(json.contains("\"fps\": 12") && json.contains("\"frames\": 4"), "{json}");
    // A second write refuses to overwrite.
    assert!(pyrograph_core::testing::cook_node(&**node, &set).unwrap_err().to_string().contains("already exists"));
}

/// Mip level `level` of `img` by 2×2 box averages (what GPUs and texture tools build), odd edges dropped.
fn mip(img: &Image, level: u32) -> Image {
    let mut m = img.clone();
    for _ in 0..level {
        let (w, h) = (m.width() / 2, m.height() / 2);
        let data = (0..w * h)
            .flat_map(|k| {
                let (x, y) = (2 * (k % w), 2 * (k / w));
                let px = [m.pixel(x, y), m.pixel(x + 1, y), m.pixel(x, y + 1), m.pixel(x + 1, y + 1)];
                (0..4).map(move |c| px.iter().map(|p| p[c]).sum::<f32>() / 4.0)
            })
            .collect();
        m = Image::from_vec(w, h, Channels::Rgba, data).unwrap();
    }
    m
}

/// A bilinear sample of `img` at (x, y) in pixels (texel centres at k + 0.5), clamped at the sheet's edge.
fn bilinear(img: &Image, x: f32, y: f32) -> [f32; 4] {
    let (fx, fy) = (x - 0.5, y - 0.5);
    let (x0, y0) = (fx.floor(), fy.floor());
    let (tx, ty) = (fx - x0, fy - y0);
    let at = |dx: f32, dy: f32| {
        let px = ((x0 + dx).max(0.0) as u32).min(img.width() - 1);
        let py = ((y0 + dy).max(0.0) as u32).min(img.height() - 1);
        img.pixel(px, py)
    };
    let (a, b, c, d) = (at(0.0, 0.0), at(1.0, 0.0), at(0.0, 1.0), at(1.0, 1.0));
    std::array::from_fn(|k| {
        let w = [(1.0 - tx) * (1.0 - ty), tx * (1.0 - ty), (1.0 - tx) * ty, tx * ty];
        // A zero weight must not let a far texel's value in (0 × anything finite is 0).
        w[0] * a[k] + w[1] * b[k] + w[2] * c[k] + w[3] * d[k]
    })
}

/// Whether sampling cell `k`'s frame at mip `level` reads anything of the other cells: the sheet is
/// built twice, the other cells' frames changed, and every texel of cell k's region and a grid of
/// bilinear samples over its frame (edges included) compared.
fn bleeds(opts: &FlipbookOptions, source: (u32, u32), level: u32) -> bool {
    let frames = |seed: f32| -> Vec<Arc<Image>> {
        (0..opts.rows * opts.cols)
            .map(|i| {
                let v = if i == 0 { 0.25 } else { seed + i as f32 * 0.01 };
                Arc::new(
                    Image::from_vec(
                        source.0,
                        source.1,
                        Channels::Rgba,
                        (0..source.0 * source.1).flat_map(|_| [v, v, v, 1.0]).collect(),
                    )
                    .unwrap(),
                )
            })
            .collect()
    };
    let (a, b) = (build_flipbook(&frames(0.5), opts).unwrap(), build_flipbook(&frames(0.9), opts).unwrap());
    let s = 1u32 << level;
    let (ma, mb) = (mip(&a.sheet, level), mip(&b.sheet, level));
    // Texels whose footprint starts inside cell 0.
    for y in 0..a.cell.1.div_ceil(s) {
        for x in 0..a.cell.0.div_ceil(s) {
            if x < ma.width() && y < ma.height() && ma.pixel(x, y) != mb.pixel(x, y) {
                return true;
            }
        }
    }
    // Bilinear samples over the frame, in level-`level` pixels.
    let (x0, y0) = (a.pad as f32, a.pad as f32);
    let (x1, y1) = (x0 + a.frame.0 as f32, y0 + a.frame.1 as f32);
    for j in 0..=16 {
        for i in 0..=16 {
            let (x, y) = (x0 + (x1 - x0) * i as f32 / 16.0, y0 + (y1 - y0) * j as f32 / 16.0);
            if bilinear(&ma, x / s as f32, y / s as f32) != bilinear(&mb, x / s as f32, y / s as f32) {
                return true;
            }
        }
    }
    false
}

#[test]
fn aligned_cells_keep_every_mip_level_to_themselves() {
    // Odd frame sizes, no padding asked for: level 3 must not mix cells once mip_levels is 3.
    let opts = FlipbookOptions { rows: 2, cols: 3, mip_levels: 3, ..Default::default() };
    let l = layout((30, 21), &opts).unwrap();
    assert_eq!((l.cell, l.pad, l.frame), ((40, 32), 4, (30, 21)));
    for level in 0..=3 {
        assert!(!bleeds(&opts, (30, 21), level), "level {level} bleeds");
    }
    // The same sheet without the alignment mixes cells at level 3 (the check can fail).
    let plain = FlipbookOptions { rows: 2, cols: 3, ..Default::default() };
    assert!(bleeds(&plain, (30, 21), 3));
    // Power-of-two sheets whose cells cannot be aligned are refused, naming mip_levels.
    let e = layout((30, 30), &FlipbookOptions { rows: 3, cols: 3, power_of_two: true, mip_levels: 4, ..Default::default() })
        .map_err(NodeError::from)
        .unwrap_err()
        .to_string();
    assert!(e.contains("mip_levels") && e.contains("not multiples of 16"), "{e}");
}

#[test]
fn dilation_carries_the_edge_into_transparent_padding() {
    let frames = numbered(4, 3, 2);
    let opts = FlipbookOptions { rows: 2, cols: 2, padding: 2, dilate: true, ..Default::default() };
    let fb = build_flipbook(&frames, &opts).unwrap();
    for k in 0..4 {
        let (ox, oy) = cell_origin(k, 2, fb.cell);
        // The corner of the padding has the frame's colour with alpha 0.
        let p = fb.sheet.pixel(ox, oy);
        assert!((p[0] - k as f32 / 4.0).abs() < 1e-6 && p[3] == 0.0, "cell {k}: {p:?}");
        assert_eq!(fb.sheet.pixel(ox + 2, oy + 2)[3], 0.5);
    }
    // Premultiplied colour is not dilated (it would add light where alpha is 0).
    let pre = build_flipbook(&frames, &FlipbookOptions { alpha: AlphaMode::Premultiplied, ..opts }).unwrap();
    assert_eq!(pre.sheet.pixel(0, 0), [0.0; 4]);
}

#[test]
fn engine_sheets_decode_to_the_flow_and_say_what_to_paste() {
    let frames: Vec<Arc<Image>> = (0..4).map(|k| Arc::new(texture(64, 48, 2.0 * k as f32, -(k as f32)))).collect();
    for convention in [Convention::Unity, Convention::Unreal, Convention::HoudiniLabs] {
        let opts = FlipbookOptions { rows: 2, cols: 2, convention, ..Default::default() };
        let fb = build_flipbook(&frames, &opts).unwrap();
        // The automatic range is the largest vector: nothing clamps.
        let flows = motion_of(&frames, convention.central_vectors());
        let largest = flows.iter().flat_map(|(u, v)| u.data.iter().chain(&v.data)).fold(0.0f32, |m, x| m.max(x.abs()));
        assert!(largest > 1.0 && (fb.motion_range - largest).abs() < 1e-6, "{convention:?}: {} vs {largest}", fb.motion_range);
        // Cell 0 (the first frame) holds the motion to the next frame under every convention.
        let (u, v) = optical_flow(&frames[0], &frames[1]);
        let p = fb.motion.pixel(32, 24);
        let (dx, dy) = fb.code.decode(p[0], p[1]);
        let (fx, fy) = (u.data[24 * 64 + 32], v.data[24 * 64 + 32]);
        assert!((dx - fx).abs() < 1e-4 && (dy - fy).abs() < 1e-4, "{convention:?}: ({dx}, {dy}) vs ({fx}, {fy})");
        let about = Sidecar { frames: 4, fps: 24.0, sheet: "f.png", motion: Some("f_mv.png"), motion_bits: 16 };
        let json = sidecar_json(&fb, &opts, &about);
        assert!(json.contains(&format!("\"engine_value\": {}", fb.code.scale)), "{json}");
        assert!(json.contains(&format!("\"convention\": \"{}\"", convention.name())), "{json}");
    }
}

#[test]
fn sheets_past_the_pixel_budget_or_u32_are_refused_before_they_are_made() {
    // 64 × 64 cells of 8 × 8 frames with 256 pixels of padding: a 33,280-pixel square sheet.
    let opts = FlipbookOptions { rows: 64, cols: 64, padding: 256, ..Default::default() };
    let e = layout((8, 8), &opts).unwrap_err().to_string();
    assert!(e.contains("33280x33280") && e.contains("pixel budget") && e.contains("--max-pixels"), "{e}");
    // A frame 2^26 pixels wide overflows u32 across 64 columns: refused, not wrapped.
    let e = layout((1 << 26, 1), &FlipbookOptions { rows: 1, cols: 64, ..Default::default() }).unwrap_err().to_string();
    assert!(e.contains("pixel budget"), "{e}");
    // The power-of-two sheet is held to the budget too, and a sheet inside it is laid out.
    assert!(layout((4000, 4000), &FlipbookOptions { rows: 4, cols: 4, power_of_two: true, ..Default::default() }).is_ok());
}

#[test]
fn engine_sheets_must_split_into_whole_cells() {
    // 48-pixel frames in 6 columns: a 288-pixel sheet, rounded to 256, is 42.67 pixels a cell.
    let opts = FlipbookOptions { rows: 6, cols: 6, power_of_two: true, convention: Convention::Unity, ..Default::default() };
    let e = layout((48, 48), &opts).unwrap_err().to_string();
    assert!(e.contains("256x256") && e.contains("6 columns"), "{e}");
    // The generic sheet keeps its old layout (whole cells, the remainder left over).
    let generic = layout((48, 48), &FlipbookOptions { convention: Convention::Generic, ..opts }).unwrap();
    assert_eq!((generic.cell, generic.sheet), ((42, 42), (256, 256)));
}

#[test]
fn motion_through_non_finite_pixels_is_no_motion() {
    let code = MotionCode { div: (16.0, -16.0), scale: 1.0 };
    assert_eq!(code.encode(f32::NAN, 1.0), (0.5, 0.5));
    assert_eq!(code.encode(2.0, f32::INFINITY), (0.5, 0.5));
    assert_eq!(code.encode(4.0, 4.0), (0.75, 0.25));
}

/// Motion-vector frames: frame k moves every pixel by (k + 1, −k) pixels, over `w`×`h`.
fn vectors(n: usize, w: u32, h: u32) -> Vec<Arc<Image>> {
    (0..n)
        .map(|k| {
            let (dx, dy) = (k as f32 + 1.0, -(k as f32));
            Arc::new(Image::from_vec(w, h, Channels::Rgba, (0..w * h).flat_map(|_| [dx, dy, 0.0, 1.0]).collect()).unwrap())
        })
        .collect()
}

#[test]
fn given_motion_vectors_replace_the_optical_flow() {
    // Constant frames have no optical flow; the given vectors are what the sheet holds.
    let frames = numbered(4, 8, 8);
    let opts = FlipbookOptions { rows: 2, cols: 2, motion_range: 8.0, ..Default::default() };
    let fb = build_flipbook_with(&frames, Some(&vectors(4, 8, 8)), &opts).unwrap();
    for k in 0..4 {
        let (ox, oy) = cell_origin(k, 2, fb.cell);
        let p = fb.motion.pixel(ox + 4, oy + 4);
        let want = (0.5 + (k as f32 + 1.0) / 16.0, 0.5 - k as f32 / 16.0);
        assert!((p[0] - want.0).abs() < 1e-6 && (p[1] - want.1).abs() < 1e-6, "cell {k}: {p:?} vs {want:?}");
    }
    // The automatic range of an engine convention is the largest given vector.
    let unity = FlipbookOptions { convention: Convention::Unity, motion_range: 0.0, ..opts };
    assert_eq!(build_flipbook_with(&frames, Some(&vectors(4, 8, 8)), &unity).unwrap().motion_range, 4.0);
    assert!(build_flipbook(&frames, &opts).unwrap().motion.data().chunks(4).all(|p| p[0] == 0.5 && p[1] == 0.5));
}

#[test]
fn motion_vectors_that_do_not_fit_the_clip_are_errors_naming_the_port() {
    let frames = numbered(4, 8, 8);
    let opts = FlipbookOptions { rows: 2, cols: 2, ..Default::default() };
    let error =
        |v: Vec<Arc<Image>>| build_flipbook_with(&frames, Some(&v), &opts).map_err(NodeError::from).unwrap_err().to_string();
    let e = error(vectors(3, 8, 8));
    assert!(e.contains("motion_vectors") && e.contains("has 3 frames but the clip has 4"), "{e}");
    let mut v = vectors(4, 8, 8);
    v[2] = vectors(1, 4, 8).remove(0);
    let e = error(v);
    assert!(e.contains("motion_vectors") && e.contains("frame 2 is 4x8"), "{e}");
    let mut v = vectors(4, 8, 8);
    v[1] = Arc::new(Image::new(8, 8, Channels::Gray));
    assert!(error(v).contains("frame 1 is gray"));
    let mut v = vectors(4, 8, 8);
    let mut bad = (*v[3]).clone();
    bad.data_mut()[9] = f32::NAN;
    v[3] = Arc::new(bad);
    let e = error(v);
    assert!(e.contains("frame 3 holds a non-finite vector"), "{e}");
}
