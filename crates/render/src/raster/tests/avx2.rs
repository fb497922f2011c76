//! The AVX2 kernels against the portable code they replace: bit for bit, on CPUs with AVX2.

use glam::{Vec2, Vec3};
use pyrograph_core::{Channels, Image};
use pyrograph_testing::lcg;

use super::support::screen_view;
use crate::raster::fan::envelope;
use crate::raster::isa::{Avx2, Portable};
use crate::raster::lanes::SMALL_LANES;
use crate::raster::tiles::raster_tri;
use crate::raster::{BAND_ROWS, Band, Blend, DrawList, SUB, SVert, Vertex, ceil_sub, floor_sub, raster_band_generic, round_i64};

/// AVX2 where the CPU has it. Without it the comparison cannot run and says so — unless
/// `PYROGRAPH_REQUIRE_AVX2` is set (`.ci/run` sets it when /proc/cpuinfo lists avx2): then a
/// detection that misses AVX2 fails the test instead of letting it pass as skipped.
fn avx2_or_skip(what: &str) -> Option<Avx2> {
    let found = Avx2::detect();
    if found.is_none() {
        assert!(
            std::env::var_os("PYROGRAPH_REQUIRE_AVX2").is_none(),
            "PYROGRAPH_REQUIRE_AVX2 is set, but AVX2 was not detected: the AVX2 {what} would go untested"
        );
        eprintln!("skipped: this CPU has no AVX2, so only the portable {what} runs");
    }
    found
}

#[test]
fn the_avx2_envelope_is_bit_identical_to_the_portable_one() {
    let Some(avx2) = avx2_or_skip("envelope") else { return };
    // Every edge count a fan row can have up to 13 (each remainder of the four chains),
    // offsets and slopes of both signs, blocks left and right of the centre.
    let mut seed = 3u64;
    let mut lowered = 0;
    for edges in 0..=13 {
        for _ in 0..200 {
            let env: Vec<[f32; 2]> = (0..edges).map(|_| [2.0 * lcg(&mut seed) - 0.5, 0.6 * lcg(&mut seed) - 0.3]).collect();
            let base = 40.0 * lcg(&mut seed) - 20.0;
            let portable = envelope(Portable, &env, base);
            let vector = envelope(avx2, &env, base);
            assert_eq!(portable.map(f32::to_bits), vector.map(f32::to_bits), "{edges} edges at {base}");
            lowered += usize::from(portable.iter().any(|v| v.is_finite()));
        }
    }
    // Guard against a vacuous pass: all rows but the empty ones have a finite envelope.
    assert_eq!(lowered, 13 * 200);
}

#[test]
fn particles_rasterize_bit_identically_with_and_without_avx2() {
    let Some(avx2) = avx2_or_skip("particle path") else { return };
    // Particles from under a pixel to 40 px wide, 3 to 24 sides, additive in range (the
    // AVX2 blend path), additive out of range and "over", some over an opaque triangle
    // (the depth-tested path), spans of every length modulo the 8-pixel block.
    let view = screen_view(96, 64);
    let mut list = DrawList::new(&view);
    list.triangle(
        [
            Vertex::new(Vec3::new(-3.0, -3.0, -1.0), [0.2, 0.3, 0.4, 1.0]),
            Vertex::new(Vec3::new(0.5, -3.0, -1.0), [0.2, 0.3, 0.4, 1.0]),
            Vertex::new(Vec3::new(-3.0, 0.5, -1.0), [0.2, 0.3, 0.4, 1.0]),
        ],
        Blend::Opaque,
    );
    let mut seed = 11u64;
    for k in 0..600 {
        let center = Vec3::new(6.0 * lcg(&mut seed) - 3.0, 4.0 * lcg(&mut seed) - 2.0, lcg(&mut seed) - 0.5);
        let half = Vec2::new(0.01 + 0.6 * lcg(&mut seed), 0.01 + 0.6 * lcg(&mut seed));
        let sides = 3 + (lcg(&mut seed) * 22.0) as u32;
        let (c, e) =
            ([lcg(&mut seed), lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)], [lcg(&mut seed), 0.5, 0.1, 0.3 * lcg(&mut seed)]);
        let (blend, c) = match k % 5 {
            3 => (Blend::Additive, [1.5, c[1], c[2], c[3]]),
            4 => (Blend::Over, c),
            _ => (Blend::Additive, c),
        };
        list.particle(center, half, sides, c, e, blend);
    }
    let frame = |isa: Option<Avx2>| {
        let (w, rows) = (96usize, 64usize);
        let (mut color, mut depth) = (vec![[0.05, 0.0, 0.1, 1.0]; w * rows], vec![1.0f32; w * rows]);
        for (bi, (c, d)) in color.chunks_mut(w * BAND_ROWS).zip(depth.chunks_mut(w * BAND_ROWS)).enumerate() {
            let y0 = bi * BAND_ROWS;
            let mut band = Band { y1: y0 + c.len() / w, color: c, depth: d, width: w, y0, has_opaque: false };
            let lists = std::slice::from_ref(&list);
            match isa {
                Some(avx2) => avx2.raster_band(lists, &view, bi, &mut band),
                None => raster_band_generic(Portable, lists, &view, bi, &mut band),
            }
        }
        color.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>()
    };
    let (portable, vector) = (frame(None), frame(Some(avx2)));
    let lit = portable.chunks(4).filter(|p| p[..3] != [0.05f32.to_bits(), 0, 0.1f32.to_bits()]).count();
    assert!(lit > 96 * 64 / 2, "most of the frame is drawn ({lit} pixels)");
    assert!(portable == vector, "AVX2 and portable frames differ");
}

#[test]
fn small_triangles_rasterize_bit_identically_to_the_general_loop() {
    // Random triangles up to 9 px wide (some take the 8-lane row path, some are too wide)
    // over a band, textured and not, with each blend and with a depth buffer to test against:
    // the row path must give exactly the same colours and depths as the per-pixel loop.
    let texture = Image::from_vec(5, 3, Channels::Rgba, (0..60).map(|i| (i % 7) as f32 / 6.0).collect()).unwrap();
    let (w, h) = (48usize, 16usize);
    let mut seed = 7u64;
    let mut small_path = 0;
    for blend in [Blend::Over, Blend::Additive, Blend::Opaque] {
        for textured in [false, true] {
            let depth0: Vec<f32> = (0..w * h).map(|_| 0.3 + 0.7 * lcg(&mut seed)).collect();
            let mut runs = Vec::new();
            // The per-pixel loop, the tiles in portable code, and in AVX2 where the CPU has it.
            let avx2 = avx2_or_skip("tile path");
            for (small, vector) in [(false, false), (true, false), (true, true)] {
                let isa = match (vector, avx2) {
                    (false, _) => None,
                    (true, Some(avx2)) => Some(avx2),
                    (true, None) => continue,
                };
                let (mut color, mut depth) = (vec![[0.1, 0.2, 0.3, 0.4]; w * h], depth0.clone());
                let mut band = Band { color: &mut color, depth: &mut depth, width: w, y0: 16, y1: 32, has_opaque: true };
                let mut s = 99u64;
                for _ in 0..400 {
                    let (cx, cy) = (-2.0 + 52.0 * lcg(&mut s), 13.0 + 22.0 * lcg(&mut s));
                    let vert = |s: &mut u64| {
                        let (x, y) = (cx + 9.0 * lcg(s) - 4.5, cy + 6.0 * lcg(s) - 3.0);
                        let iw = 0.5 + lcg(s);
                        let c = [lcg(s), lcg(s), lcg(s), lcg(s)].map(|v| v * iw);
                        SVert {
                            x: round_i64(x * 256.0),
                            y: round_i64(y * 256.0),
                            z: lcg(s),
                            iw,
                            c,
                            uv: [lcg(s) * iw, lcg(s) * iw],
                        }
                    };
                    let [a, b, c] = [vert(&mut s), vert(&mut s), vert(&mut s)];
                    let tex = textured.then_some(&texture);
                    if let (true, Some(avx2)) = (small, isa) {
                        raster_tri::<true, _>(avx2, &mut band, &a, &b, &c, blend, tex);
                    } else if small {
                        raster_tri::<true, _>(Portable, &mut band, &a, &b, &c, blend, tex);
                    } else {
                        raster_tri::<false, _>(Portable, &mut band, &a, &b, &c, blend, tex);
                        let xs = [a.x, b.x, c.x];
                        let (lo, hi) = (xs.into_iter().min().unwrap_or(0), xs.into_iter().max().unwrap_or(0));
                        small_path += usize::from(floor_sub(hi - SUB / 2) - ceil_sub(lo - SUB / 2) < SMALL_LANES as i64);
                    }
                }
                runs.push((color, depth));
            }
            let bits = |(c, d): &(Vec<[f32; 4]>, Vec<f32>)| {
                (c.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>(), d.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
            };
            assert!(runs[0].0.iter().any(|p| *p != [0.1, 0.2, 0.3, 0.4]), "{blend:?}: nothing was drawn");
            for run in &runs[1..] {
                assert_eq!(bits(&runs[0]), bits(run), "{blend:?}, textured {textured}");
            }
        }
    }
    assert!(small_path > 1000, "only {small_path} triangles were narrow enough for the row path");
}
