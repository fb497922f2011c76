use super::*;
use pyrograph_core::Channels;

/// A `w × h` RGBA frame: a textured wall (brightness 0.3–0.45), a still orange lamp of radius
/// 6 at `lamp` and a flame at `flame` whose radius and brightness change with `t`.
fn scene(w: u32, h: u32, lamp: (f32, f32), flame: (f32, f32), t: usize) -> Image {
    let r_flame = 7.0 + (t % 3) as f32 * 1.5;
    let glow = 0.8 + 0.2 * ((t * 7) % 5) as f32 / 4.0;
    let mut data = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32, y as f32);
            let wall = 0.3 + 0.15 * (((x * 7 + y * 13) % 11) as f32 / 10.0);
            let px = if (fx - lamp.0).hypot(fy - lamp.1) < 6.0 {
                [1.0, 0.6, 0.1]
            } else if (fx - flame.0).hypot((fy - flame.1) / 2.0) < r_flame {
                [glow, 0.6 * glow, 0.1 * glow]
            } else {
                [wall, 0.8 * wall, 0.6 * wall]
            };
            data.extend_from_slice(&[px[0], px[1], px[2], 1.0]);
        }
    }
    Image::from_vec(w, h, Channels::Rgba, data).unwrap()
}

/// Pixels brighter than 0.6 in red: the lamp and the flame, as a colour mask would take them.
fn bright(img: &Image) -> Mask {
    let data = img.data().chunks_exact(4).map(|p| if p[0] > 0.6 { 255 } else { 0 }).collect();
    Mask::from_vec(img.width(), img.height(), data).unwrap()
}

fn cook(frames: Vec<Image>, min_contrast: f64) -> (FireCuesOut, CookCtx) {
    let masks = frames.iter().map(|f| Value::Mask(Arc::new(bright(f)))).collect();
    let images = frames.into_iter().map(|f| Value::Image(Arc::new(f))).collect();
    let node = FireCues {
        clip: ClipOf::new(Clip::from_frames(PortType::Image, 24.0, images)),
        mask: ClipOf::new(Clip::from_frames(PortType::Mask, 24.0, masks)),
        window: 8,
        min_flicker: 0.003,
        min_contrast,
        reach: 1,
    };
    let ctx = CookCtx::new();
    (node.cook(&ctx).unwrap(), ctx)
}

fn mask_at(out: &FireCuesOut, i: usize, ctx: &CookCtx) -> Mask {
    let Value::Mask(m) = out.mask.get(i, ctx).unwrap() else { panic!("frame {i} is not a mask") };
    (*m).clone()
}

#[test]
fn a_still_lamp_of_fire_colour_is_dropped_and_the_flickering_flame_kept() {
    let frames: Vec<Image> = (0..8).map(|t| scene(96, 80, (20.0, 20.0), (60.0, 45.0), t)).collect();
    let (out, ctx) = cook(frames, 1.2);
    for i in [0, 4, 7] {
        let m = mask_at(&out, i, &ctx);
        assert!(!m.get(20, 20), "frame {i}: the lamp holds still and is dropped");
        assert!(m.get(60, 45), "frame {i}: the flame flickers and is kept");
    }
    let Value::Image(f) = out.flicker.get(4, &ctx).unwrap() else { panic!() };
    assert_eq!(f.size(), (96, 80));
    assert!(f.pixel(60, 52)[0] > 0.5 && f.pixel(20, 20)[0] == 0.0, "{} {}", f.pixel(60, 52)[0], f.pixel(20, 20)[0]);
}

#[test]
fn a_camera_moving_a_pixel_a_frame_is_not_flicker_within_reach() {
    // A textured plane moved one pixel right every frame: a still scene under a panning camera.
    let plane = |t: usize| Plane {
        width: 40,
        height: 30,
        data: (0..40 * 30).map(|i| ((((i % 40) + 40 - t) * 5 + (i / 40) * 3) % 7) as f32 / 7.0).collect(),
    };
    let owned: Vec<Plane> = (0..5).map(plane).collect();
    let planes: Vec<&Plane> = owned.iter().collect();
    let still = flicker_plane(&planes, 1, None);
    let inner: Vec<f32> = (2..28).flat_map(|y| (2..38).map(move |x| (x, y))).map(|(x, y)| still.data[y * 40 + x]).collect();
    assert!(inner.iter().all(|&v| v < 1e-6), "max {}", inner.iter().cloned().fold(0.0, f32::max));
    let moved = flicker_plane(&planes, 0, None);
    assert!(moved.data.iter().sum::<f32>() / 1200.0 > 0.1, "without reach the move counts");
}

#[test]
fn a_blob_no_brighter_than_its_surroundings_is_dropped() {
    let frames: Vec<Image> = (0..6).map(|t| scene(96, 80, (20.0, 20.0), (60.0, 45.0), t)).collect();
    // The flame is about 2.5 times as bright as the wall: asked for 4, it is not fire.
    let (out, ctx) = cook(frames, 4.0);
    assert!(!mask_at(&out, 3, &ctx).get(60, 45));
}

#[test]
fn a_short_clip_passes_unchanged_with_a_warning_and_mismatched_inputs_are_refused() {
    let frames: Vec<Image> = (0..2).map(|t| scene(48, 40, (10.0, 10.0), (30.0, 25.0), t)).collect();
    let want = bright(&frames[1]);
    let (out, ctx) = cook(frames.clone(), 1.2);
    assert_eq!(mask_at(&out, 1, &ctx).data(), want.data());
    assert!(ctx.warnings()[0].message.contains("no flicker to judge"), "{:?}", ctx.warnings());
    let node = FireCues {
        clip: ClipOf::new(Clip::from_frames(
            PortType::Image,
            24.0,
            frames.into_iter().map(|f| Value::Image(Arc::new(f))).collect(),
        )),
        mask: ClipOf::new(Clip::from_frames(PortType::Mask, 24.0, vec![Value::Mask(Arc::new(want))])),
        window: 8,
        min_flicker: 0.003,
        min_contrast: 1.2,
        reach: 1,
    };
    let err = node.cook(&CookCtx::new()).err().unwrap().to_string();
    assert!(err.contains("the mask has 1 frames but the clip has 2"), "{err}");
}

#[test]
fn large_frames_are_measured_on_a_halved_plane() {
    let img = Image::new(2000, 1000, Channels::Gray);
    let (p, halvings) = work_plane(&img);
    assert_eq!((p.width, p.height, halvings), (500, 250, 2));
}

#[test]
fn a_scene_filmed_three_stops_darker_is_judged_alike() {
    let dark = |img: Image| {
        let mut img = img;
        img.data_mut().chunks_exact_mut(4).for_each(|p| p[..3].iter_mut().for_each(|v| *v /= 8.0));
        img
    };
    let frames: Vec<Image> = (0..8).map(|t| dark(scene(96, 80, (20.0, 20.0), (60.0, 45.0), t))).collect();
    // The colour mask of the bright scene, as per-clip thresholds would take the dark one.
    let masks: Vec<Value> =
        (0..8).map(|t| Value::Mask(Arc::new(bright(&scene(96, 80, (20.0, 20.0), (60.0, 45.0), t))))).collect();
    let node = FireCues {
        clip: ClipOf::new(Clip::from_frames(
            PortType::Image,
            24.0,
            frames.into_iter().map(|f| Value::Image(Arc::new(f))).collect(),
        )),
        mask: ClipOf::new(Clip::from_frames(PortType::Mask, 24.0, masks)),
        window: 8,
        min_flicker: 0.003,
        min_contrast: 1.2,
        reach: 1,
    };
    let ctx = CookCtx::new();
    let out = node.cook(&ctx).unwrap();
    let m = mask_at(&out, 4, &ctx);
    assert!(m.get(60, 45) && !m.get(20, 20));
}

#[test]
fn a_frames_window_ends_at_it_except_at_the_clips_start() {
    assert_eq!(window_of(20, 8, 100), (12, 20));
    assert_eq!(window_of(3, 8, 100), (0, 8));
    assert_eq!(window_of(3, 8, 5), (0, 4));
    assert_eq!(window_of(0, 8, 1), (0, 0));
}

#[test]
fn a_moving_border_with_no_picture_is_not_flicker_over_a_longer_clip() {
    // A stabilized plate: the lamp sits at the frame's left edge, where the border brought in from
    // outside the frame (transparent black) covers 4 more columns in odd frames than in even
    // ones. 20 frames, more than the window of 8.
    let frames: Vec<Image> = (0..20)
        .map(|t| {
            let mut img = scene(96, 80, (8.0, 40.0), (60.0, 45.0), t);
            let border = if t % 2 == 1 { 5 } else { 1 };
            img.data_mut().chunks_exact_mut(4).enumerate().filter(|(i, _)| i % 96 < border).for_each(|(_, p)| p.fill(0.0));
            img
        })
        .collect();
    let (out, ctx) = cook(frames, 1.2);
    for i in [2, 9, 15, 19] {
        let m = mask_at(&out, i, &ctx);
        assert!(!m.get(8, 40), "frame {i}: the lamp holds still; the border moving over it is not flicker");
        assert!(m.get(60, 45), "frame {i}: the flame flickers and is kept");
    }
}
