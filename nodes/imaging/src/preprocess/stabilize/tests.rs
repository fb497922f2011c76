use super::*;
use pyrograph_core::PortType;

/// A `w × h` RGBA wall with texture at several scales (brightness 0.1–0.6) and, when `flame`, a
/// bright blob at its centre that changes with `t`.
fn wall(w: u32, h: u32, flame: bool, t: usize) -> Image {
    let mut data = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32, y as f32);
            let v = 0.35
                + 0.12 * (fx * 0.11 + 0.7 * (fy * 0.05).sin()).sin()
                + 0.08 * (fy * 0.23 + fx * 0.04).cos()
                + 0.05 * (((x * 31 + y * 17) % 13) as f32 / 12.0 - 0.5);
            let r = (fx - w as f32 / 2.0).hypot((fy - h as f32 / 2.0) * 0.5);
            let v = if flame && r < 10.0 + (t % 4) as f32 * 3.0 { 1.0 } else { v };
            data.extend_from_slice(&[v, v * 0.8, v * 0.6, 1.0]);
        }
    }
    Image::from_vec(w, h, Channels::Rgba, data).unwrap()
}

#[test]
fn motions_chain_and_undo() {
    let a = Rigid { angle: 0.03, shift: [2.0, -1.0] };
    let b = Rigid { angle: -0.01, shift: [0.5, 3.0] };
    let c = [50.0, 40.0];
    let p = [12.0, 70.0];
    let both = a.then(b).apply(p, c);
    let step = b.apply(a.apply(p, c), c);
    assert!((both[0] - step[0]).abs() < 1e-9 && (both[1] - step[1]).abs() < 1e-9, "{both:?} {step:?}");
    let back = a.inverse().apply(a.apply(p, c), c);
    assert!((back[0] - p[0]).abs() < 1e-9 && (back[1] - p[1]).abs() < 1e-9);
}

#[test]
fn a_turned_and_shifted_frame_is_measured_to_a_tenth_of_a_pixel() {
    let a = wall(320, 240, false, 0);
    for truth in [
        Rigid { angle: 0.0, shift: [3.0, -2.0] },
        Rigid { angle: 0.02, shift: [-6.5, 4.25] },
        Rigid { angle: -0.035, shift: [1.0, 9.0] },
    ] {
        // b shows at x what a has at truth⁻¹(x): a point of a at p is in b at truth(p).
        let b = warp(&a, truth.inverse());
        let m = frame_motion(&a, &b).expect("textured");
        let err = corner_shift(m.then(truth.inverse()), (320, 240));
        assert!(err < 0.15, "{truth:?} measured {m:?}: corners off by {err:.3} px");
    }
}

#[test]
fn a_flame_on_black_is_not_a_camera_motion() {
    let blob = |t: usize| {
        let mut img = wall(160, 120, true, t);
        img.data_mut().chunks_exact_mut(4).for_each(|p| {
            if p[0] < 0.9 {
                p[..3].fill(0.0);
            }
        });
        img
    };
    assert_eq!(frame_motion(&blob(0), &blob(1)), None);
    // Filmed three stops darker: the flame is still the brightest thing and still left out.
    let dim = |t: usize| {
        let mut img = blob(t);
        img.data_mut().chunks_exact_mut(4).for_each(|p| p[..3].iter_mut().for_each(|v| *v *= 0.4));
        img
    };
    assert_eq!(frame_motion(&dim(0), &dim(1)), None);
}

#[test]
fn a_shaken_clip_is_held_on_its_first_frame_and_a_flame_left_to_flicker() {
    let shakes = [
        Rigid::default(),
        Rigid { angle: 0.02, shift: [4.0, -3.0] },
        Rigid { angle: -0.015, shift: [-5.0, 2.0] },
        Rigid { angle: 0.01, shift: [2.5, 6.0] },
    ];
    let frames: Vec<Value> =
        shakes.iter().enumerate().map(|(t, s)| Value::Image(Arc::new(warp(&wall(240, 180, true, t), s.inverse())))).collect();
    let node = Stabilize { clip: ClipOf::new(Clip::from_frames(PortType::Image, 24.0, frames)), smoothing: 0.0 };
    let ctx = CookCtx::new();
    let out = node.cook(&ctx).unwrap();
    assert!(out.correction > 5.0, "{}", out.correction);
    let want: Vec<Image> = (0..4).map(|t| wall(240, 180, true, t)).collect();
    let shaken: Vec<Image> = shakes.iter().enumerate().map(|(t, s)| warp(&wall(240, 180, true, t), s.inverse())).collect();
    // Mean difference from the unshaken frame away from the borders brought in from outside
    // (resampling twice blurs the flame's sharp edge, so not the worst pixel).
    let off = |got: &Image, want: &Image| {
        let mut sum = 0.0f32;
        for y in 20..160 {
            for x in 20..220 {
                sum += (got.pixel(x, y)[0] - want.pixel(x, y)[0]).abs();
            }
        }
        sum / (140.0 * 200.0)
    };
    for (i, w) in want.iter().enumerate() {
        let Value::Image(got) = out.clip.get(i, &ctx).unwrap() else { panic!() };
        let (held, before) = (off(&got, w), off(&shaken[i], w));
        assert!(held < 0.02 && (i == 0 || before > 3.0 * held), "frame {i}: off by {held} held, {before} shaken");
    }
}

#[test]
fn a_smoothed_path_keeps_a_pan_and_removes_the_shake() {
    let path: Vec<Rigid> =
        (0..60).map(|i| Rigid { angle: 0.0, shift: [i as f64 + if i % 2 == 0 { 3.0 } else { -3.0 }, 0.0] }).collect();
    let smooth = smooth_path(&path, 4.0);
    for (i, s) in smooth.iter().enumerate().take(45).skip(15) {
        assert!((s.shift[0] - i as f64).abs() < 0.2, "frame {i}: {s:?}");
    }
    assert!(smooth_path(&path, 0.0).iter().all(|r| *r == Rigid::default()));
}

#[test]
fn a_turning_pan_with_shake_keeps_its_smooth_path_and_loses_the_shake() {
    // The camera pans 2 px and turns 0.004 rad a frame, with a shake of ±3 px and ±0.012 rad
    // alternating on top: what is left between held frames is the pan's step.
    let n = 12;
    let truth: Vec<Rigid> = (0..n)
        .map(|i| {
            let jitter = if i % 2 == 0 { 1.0 } else { -1.0 };
            Rigid { angle: 0.004 * i as f64 + 0.012 * jitter, shift: [2.0 * i as f64 + 3.0 * jitter, -1.5 * jitter] }
        })
        .collect();
    let scene = wall(240, 180, false, 0);
    let frames: Vec<Value> = truth.iter().map(|m| Value::Image(Arc::new(warp(&scene, m.inverse())))).collect();
    let node = Stabilize { clip: ClipOf::new(Clip::from_frames(PortType::Image, 24.0, frames)), smoothing: 2.0 };
    let ctx = CookCtx::new();
    let out = node.cook(&ctx).unwrap();
    let held: Vec<Arc<Image>> = (0..n)
        .map(|i| match out.clip.get(i, &ctx).unwrap() {
            Value::Image(img) => img,
            _ => panic!("frame {i}"),
        })
        .collect();
    for i in 4..8 {
        let input = frame_motion(&warp(&scene, truth[i].inverse()), &warp(&scene, truth[i + 1].inverse())).unwrap();
        let step = frame_motion(&held[i], &held[i + 1]).unwrap();
        assert!((input.angle - 0.004).abs() > 0.02, "frame {i}: the input shakes: {input:?}");
        assert!((step.angle - 0.004).abs() < 0.003, "frame {i}: turned {} between held frames", step.angle);
        let len = step.shift[0].hypot(step.shift[1]);
        assert!((len - 2.0).abs() < 0.6, "frame {i}: moved {len:.2} px between held frames: {step:?}");
    }
}

#[test]
fn dim_noisy_footage_from_a_tripod_is_not_a_camera_motion() {
    // Faint texture (±0.02) under 8-bit sensor noise (up to two steps either way, new in every
    // frame): the residual is mostly noise, and no sub-pixel motion may pass for the camera's.
    let frame = |seed: u64| {
        let mut s = seed;
        let mut data = Vec::with_capacity(640 * 360 * 4);
        for y in 0..360u32 {
            for x in 0..640u32 {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let noise = ((s % 5) as f32 - 2.0) / 255.0;
                let v = 0.2 + 0.02 * (x as f32 * 0.13).sin() * (y as f32 * 0.09).cos() + noise;
                let v = (v * 255.0).round() / 255.0;
                data.extend_from_slice(&[v, v * 0.8, v * 0.6, 1.0]);
            }
        }
        Image::from_vec(640, 360, Channels::Rgba, data).unwrap()
    };
    for (a, b) in [(1, 2), (3, 4), (5, 6)] {
        let m = frame_motion(&frame(a), &frame(b));
        assert!(m.is_none_or(is_identity), "seeds {a}, {b}: {m:?}");
    }
}

#[test]
fn a_dim_wall_shaken_by_a_few_pixels_is_measured() {
    // The wall at 40 % of its brightness: a 3 px shake changes its pixels by about 0.015, under a
    // fixed agreement level of 0.03, so only a level set by the footage's own residual sees it.
    let dim = |img: Image| {
        let mut img = img;
        img.data_mut().chunks_exact_mut(4).for_each(|p| p[..3].iter_mut().for_each(|v| *v *= 0.4));
        img
    };
    let a = dim(wall(320, 240, false, 0));
    let truth = Rigid { angle: 0.004, shift: [3.0, -2.0] };
    let b = warp(&a, truth.inverse());
    let m = frame_motion(&a, &b).expect("textured");
    let err = corner_shift(m.then(truth.inverse()), (320, 240));
    assert!(err < 0.3, "measured {m:?}: corners off by {err:.3} px");
}
