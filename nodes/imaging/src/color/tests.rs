//! Tests of the colouring in `color/`: original and synthetic colouring, ramps and alpha.

use super::*;
use proptest::prelude::*;
use pyrograph_core::declare::Port;
use pyrograph_core::{Mask, Value};

use crate::testing::{gray, rgba};

fn solid(w: u32, h: u32, c: [f32; 3]) -> Image {
    let data: Vec<f32> = (0..w * h).flat_map(|_| [c[0], c[1], c[2], 1.0]).collect();
    rgba(w, h, &data)
}

fn px(img: &Image, x: u32) -> [f32; 4] {
    let p = img.pixel(x, 0);
    [p[0], p[1], p[2], p[3]]
}

fn close(a: [f32; 4], b: [f32; 4]) -> bool {
    a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-5)
}

#[test]
fn algorithm2_copies_above_and_fades_at_and_below_the_threshold() {
    // Threshold 30: source values (×255) 60, 31, 30, 15, 0.
    let src = gray(5, 1, &[60.0 / 255.0, 31.0 / 255.0, 30.0 / 255.0, 15.0 / 255.0, 0.0]);
    let orig = solid(5, 1, [0.8, 0.4, 0.2]);
    let out = original_coloring(&src, &orig, 30.0, ColoringLayers::default()).unwrap();
    assert!(close(px(&out, 0), [0.8, 0.4, 0.2, 1.0]));
    assert!(close(px(&out, 1), [0.8, 0.4, 0.2, 1.0]));
    // At the threshold: scaleSrc = 1, the original colour (continuous with the branch above).
    assert!(close(px(&out, 2), [0.8, 0.4, 0.2, 1.0]));
    // Half the threshold: half the colour over the empty destination.
    assert!(close(px(&out, 3), [0.4, 0.2, 0.1, 1.0]));
    assert!(close(px(&out, 4), [0.0, 0.0, 0.0, 1.0]));
}

#[test]
fn algorithm2_with_destination_and_smoke_saturates() {
    let src = gray(3, 1, &[100.0 / 255.0, 15.0 / 255.0, 0.0]);
    let orig = solid(3, 1, [0.8, 0.4, 0.2]);
    let dest = solid(3, 1, [0.2, 0.2, 0.2]);
    let smoke = solid(3, 1, [0.1, 0.9, 0.0]);
    let layers = ColoringLayers { destination: Some(&dest), smoke: Some(&smoke), custom_mask: None };
    let out = original_coloring(&src, &orig, 30.0, layers).unwrap();
    // Above: the original, smoke and destination ignored.
    assert!(close(px(&out, 0), [0.8, 0.4, 0.2, 1.0]));
    // s = 0.5: 0.5·orig + 0.5·(dest + smoke).
    assert!(close(px(&out, 1), [0.55, 0.75, 0.2, 1.0]));
    // s = 0: dest + smoke, green saturated at 1.
    let smoke_hot = solid(3, 1, [0.1, 0.95, 0.0]);
    let layers = ColoringLayers { destination: Some(&dest), smoke: Some(&smoke_hot), custom_mask: None };
    let out = original_coloring(&src, &orig, 30.0, layers).unwrap();
    assert!(close(px(&out, 2), [0.3, 1.0, 0.2, 1.0]));
}

#[test]
fn black_layers_equal_disabled_layers() {
    let src = gray(4, 1, &[0.5, 0.1, 0.05, 0.0]);
    let orig = solid(4, 1, [0.9, 0.5, 0.1]);
    let black = solid(4, 1, [0.0; 3]);
    let plain = original_coloring(&src, &orig, 30.0, ColoringLayers::default()).unwrap();
    let layers = ColoringLayers { destination: Some(&black), smoke: Some(&black), custom_mask: None };
    assert_eq!(original_coloring(&src, &orig, 30.0, layers).unwrap(), plain);
}

#[test]
fn custom_mask_admits_extra_original_pixels() {
    let src = gray(2, 1, &[0.0, 0.0]);
    let orig = solid(2, 1, [0.3, 0.3, 0.3]);
    let mask = Mask::from_vec(2, 1, vec![0, 255]).unwrap();
    let layers = ColoringLayers { custom_mask: Some(&mask), ..Default::default() };
    let out = original_coloring(&src, &orig, 30.0, layers).unwrap();
    assert!(close(px(&out, 0), [0.0, 0.0, 0.0, 1.0]));
    assert!(close(px(&out, 1), [0.3, 0.3, 0.3, 1.0]));
}

#[test]
fn bad_sizes_and_thresholds_are_clear_errors() {
    let src = gray(2, 1, &[0.0, 0.0]);
    let orig = solid(3, 1, [0.3; 3]);
    let e = original_coloring(&src, &orig, 30.0, ColoringLayers::default()).map_err(NodeError::from).unwrap_err().to_string();
    assert!(e.contains("'original' is 3x1 but the source is 2x1"), "{e}");
    let orig = solid(2, 1, [0.3; 3]);
    for bad in [-1.0, 256.0, f64::NAN] {
        let e = original_coloring(&src, &orig, bad, ColoringLayers::default()).map_err(NodeError::from).unwrap_err().to_string();
        assert!(e.contains("threshold") && e.contains("outside 0–255"), "{e}");
    }
    let smoke = solid(1, 1, [0.0; 3]);
    let layers = ColoringLayers { smoke: Some(&smoke), ..Default::default() };
    assert!(original_coloring(&src, &orig, 30.0, layers).map_err(NodeError::from).unwrap_err().to_string().contains("'smoke'"));
}

#[test]
fn zero_threshold_does_not_divide_by_zero() {
    let src = gray(2, 1, &[0.0, 0.01]);
    let orig = solid(2, 1, [0.5; 3]);
    let out = original_coloring(&src, &orig, 0.0, ColoringLayers::default()).unwrap();
    assert!(out.data().iter().all(|v| v.is_finite()));
    assert!(close(px(&out, 1), [0.5, 0.5, 0.5, 1.0]));
}

#[test]
fn hls_of_pure_colours() {
    let cases = [
        ([1.0, 0.0, 0.0], [0.0, 0.5, 1.0]),
        ([0.0, 1.0, 0.0], [120.0, 0.5, 1.0]),
        ([0.0, 0.0, 1.0], [240.0, 0.5, 1.0]),
        ([1.0, 1.0, 0.0], [60.0, 0.5, 1.0]),
        ([1.0, 1.0, 1.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
        ([0.5, 0.5, 0.5], [0.0, 0.5, 0.0]),
    ];
    for (rgb, hls) in cases {
        let got = rgb_to_hls(rgb);
        assert!(got.iter().zip(&hls).all(|(a, b)| (a - b).abs() < 1e-5), "{rgb:?}: {got:?} vs {hls:?}");
        let back = hls_to_rgb(got);
        assert!(back.iter().zip(&rgb).all(|(a, b)| (a - b).abs() < 1e-5), "{rgb:?} -> {back:?}");
    }
}

proptest! {
    #[test]
    fn hls_round_trips_mixed_colours(r in 0.0f32..=1.0, g in 0.0f32..=1.0, b in 0.0f32..=1.0) {
        let back = hls_to_rgb(rgb_to_hls([r, g, b]));
        prop_assert!(back.iter().zip(&[r, g, b]).all(|(x, y)| (x - y).abs() < 1e-4), "{:?} -> {:?}", [r, g, b], back);
    }

    #[test]
    fn premultiply_then_unpremultiply_is_identity_where_alpha_is_positive(
        c in proptest::array::uniform3(0.0f32..=1.0), a in 0.01f32..=1.0
    ) {
        let img = rgba(1, 1, &[c[0], c[1], c[2], a]);
        let pre = premultiply(&img);
        prop_assert!((pre.data()[0] - c[0] * a).abs() < 1e-6);
        prop_assert_eq!(pre.data()[3], a);
        let back = unpremultiply(&pre);
        prop_assert!(back.data().iter().zip(img.data()).all(|(x, y)| (x - y).abs() < 1e-4));
    }
}

#[test]
fn set_alpha_takes_the_matte() {
    let out = set_alpha(&solid(2, 1, [0.5; 3]), &gray(2, 1, &[0.25, 2.0])).unwrap();
    assert_eq!(out.data(), &[0.5, 0.5, 0.5, 0.25, 0.5, 0.5, 0.5, 1.0]);
    assert!(
        set_alpha(&solid(2, 1, [0.5; 3]), &gray(1, 1, &[0.0]))
            .map_err(NodeError::from)
            .unwrap_err()
            .to_string()
            .contains("'matte'")
    );
}

#[test]
fn declared_defaults_are_the_ports_defaults() {
    use crate::bloom::BloomParams;
    use crate::flipbook::FlipbookOptions;
    use crate::smoke::{Difference, SmokeParams};
    let bloom =
        BloomParams { passes: 4, sigma: 32.0, shrink: 0.5, strength: 0.4, tint: false, tint_color: [1.0, 0.45, 0.1, 1.0] };
    assert_eq!(BloomParams::default(), bloom);
    let smoke = SmokeParams { difference: Difference::Signed, threshold: 8.0, blur: 1.5, color: [0.45, 0.45, 0.45, 1.0] };
    assert_eq!(SmokeParams::default(), smoke);
    let layout =
        FlipbookOptions { rows: 8, cols: 8, padding: 0, power_of_two: false, alpha: AlphaMode::Straight, ..Default::default() };
    assert_eq!(FlipbookOptions::default(), layout);
}

#[test]
fn alpha_mode_is_an_enum_port() {
    assert_eq!(AlphaMode::from_value(&Value::Enum("premultiplied".into())), Ok(AlphaMode::Premultiplied));
    assert!(
        AlphaMode::from_value(&Value::Enum("dim".into())).unwrap_err().contains("unknown option 'dim' (straight, premultiplied)")
    );
    assert_eq!(AlphaMode::options(), AlphaMode::NAMES);
}

#[test]
fn unpremultiply_of_zero_alpha_is_black() {
    let back = unpremultiply(&rgba(1, 1, &[0.5, 0.5, 0.5, 0.0]));
    assert_eq!(back.data(), &[0.0, 0.0, 0.0, 0.0]);
}

#[test]
fn synthetic_keeps_lightness_and_takes_the_blend_hue() {
    let src = gray(3, 1, &[0.0, 0.5, 1.0]);
    let out = synthetic_coloring(&src, &Blend::Solid([1.0, 0.5, 0.0])).unwrap();
    let mid = out.pixel(1, 0);
    let hls = rgb_to_hls([mid[0], mid[1], mid[2]]);
    assert!((hls[0] - 30.0).abs() < 1e-3 && (hls[1] - 0.5).abs() < 1e-5 && (hls[2] - 1.0).abs() < 1e-5, "{hls:?}");
    assert_eq!(&out.pixel(0, 0)[..3], &[0.0, 0.0, 0.0]);
    assert_eq!(&out.pixel(2, 0)[..3], &[1.0, 1.0, 1.0]);
    let tex = solid(2, 1, [0.0, 0.0, 1.0]);
    assert!(
        synthetic_coloring(&src, &Blend::Texture(&tex))
            .map_err(NodeError::from)
            .unwrap_err()
            .to_string()
            .contains("'texture' is 2x1")
    );
}

#[test]
fn ramp_interpolates_and_clamps() {
    let ramp = ColorRamp::parse("0:0,0,0; 1:1,0.5,0").unwrap();
    assert_eq!(ramp.color_at(0.5), [0.5, 0.25, 0.0]);
    assert_eq!(ramp.color_at(-1.0), [0.0, 0.0, 0.0]);
    assert_eq!(ramp.color_at(2.0), [1.0, 0.5, 0.0]);
    assert!(ColorRamp::parse(DEFAULT_RAMP).is_ok());
    assert!(ColorRamp::parse("0:1,2").unwrap_err().contains("needs 3"));
    assert!(ColorRamp::parse("").is_err());
    let ramped = synthetic_coloring(&gray(1, 1, &[0.5]), &Blend::RampDirect(&ramp)).unwrap();
    assert_eq!(ramped.data(), &[0.5, 0.25, 0.0, 1.0]);
}
