//! Values between pyrograph and numpy: images, masks and point lists through the arena (their
//! shapes and dtypes checked, sizes refused before allocating), parameters as JSON.

use std::sync::Arc;

use pyrograph_core::value::{Place, Points, PortType};
use pyrograph_core::{Channels, Image, Mask, Value};
use serde_json::{Value as Json, json};

use crate::arena::Arena;
use crate::protocol::{ArraySpec, OutputSpec};

/// The most points a plugin may return: 16 Mi (512 MiB of float64 rows).
pub const MAX_POINTS: u64 = 1 << 24;

/// Writes an image at `offset` as float32 `(H, W)` or `(H, W, 4)`.
pub fn put_image(arena: &Arena, offset: u64, img: &Image) -> std::io::Result<ArraySpec> {
    arena.put(offset, bytemuck::cast_slice(img.data()))?;
    let mut shape = vec![u64::from(img.height()), u64::from(img.width())];
    if img.channels() == Channels::Rgba {
        shape.push(4);
    }
    Ok(ArraySpec { offset, shape, dtype: "<f4".into() })
}

/// Writes a mask at `offset` as uint8 `(H, W)`.
pub fn put_mask(arena: &Arena, offset: u64, mask: &Mask) -> std::io::Result<ArraySpec> {
    arena.put(offset, mask.data())?;
    Ok(ArraySpec { offset, shape: vec![mask.height().into(), mask.width().into()], dtype: "|u1".into() })
}

/// A parameter as the plugin function receives it (colours and vectors as lists).
pub fn param_json(v: &Value) -> Result<Json, String> {
    // JSON has no NaN or infinity: say so here rather than let the worker get a null.
    let finite = |xs: &[f64]| match xs.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(format!("{x} cannot be passed to a Python plugin: only finite numbers can")),
        None => Ok(()),
    };
    match v {
        Value::Float(x) => finite(&[*x])?,
        Value::Color(c) => finite(&c.map(f64::from))?,
        Value::Vec2(v) => finite(v)?,
        Value::Vec3(v) => finite(v)?,
        _ => {}
    }
    Ok(match v {
        Value::Float(x) => json!(x),
        Value::Int(i) => json!(i),
        Value::Bool(b) => json!(b),
        Value::String(s) | Value::Enum(s) => json!(s),
        Value::Color(c) => json!(c),
        Value::Vec2(v) => json!(v),
        Value::Vec3(v) => json!(v),
        Value::Ramp(keys) => {
            let rows: Vec<Vec<f64>> = keys
                .keys()
                .iter()
                .map(|(pos, v)| std::iter::once(*pos).chain(v[..keys.width()].iter().copied()).collect())
                .collect();
            json!(rows)
        }
        Value::Path(p) => json!(p.to_str().ok_or_else(|| format!("path {} is not valid UTF-8", p.display()))?),
        other => return Err(format!("a plugin cannot take a {} here", other.type_name())),
    })
}

/// One output value that is not a clip: an array read from the arena, or a number.
pub fn read_output(arena: &Arena, ty: &PortType, out: &OutputSpec) -> Result<Value, String> {
    match (ty, &out.array, &out.value) {
        (PortType::Image, Some(a), _) => read_image(arena, a).map(|i| Value::Image(Arc::new(i))),
        (PortType::Mask, Some(a), _) => read_mask(arena, a).map(|m| Value::Mask(Arc::new(m))),
        (PortType::Points, Some(a), _) => read_points(arena, a).map(|p| Value::Points(Arc::new(p))),
        (PortType::Float, _, Some(j)) => j.as_f64().map(Value::Float).ok_or(format!("{j} is not a number")),
        (PortType::Int, _, Some(j)) => j.as_i64().map(Value::Int).ok_or(format!("{j} is not an integer")),
        (PortType::Bool, _, Some(j)) => j.as_bool().map(Value::Bool).ok_or(format!("{j} is not true or false")),
        _ => Err(format!("the plugin returned something that is not a {ty}")),
    }
}

/// Width and height of a `(H, W)` or `(H, W, C)` array, refused before allocating when the image
/// would be over the pixel limit.
fn image_size(shape: &[u64]) -> Result<(u32, u32), String> {
    let (h, w) = (shape[0], shape[1]);
    let limit = pyrograph_core::limits::max_pixels();
    if h == 0 || w == 0 || h.saturating_mul(w) > limit || h > u64::from(u32::MAX) || w > u64::from(u32::MAX) {
        let hint = pyrograph_core::limits::raise_hint("--max-pixels", "PYROGRAPH_MAX_PIXELS", limit);
        return Err(format!("a {w} × {h} image is empty or over the pixel limit ({hint})"));
    }
    Ok((w as u32, h as u32))
}

/// An image the worker wrote.
pub fn read_image(arena: &Arena, a: &ArraySpec) -> Result<Image, String> {
    let channels = match (a.dtype.as_str(), a.shape.as_slice()) {
        ("<f4", [_, _]) => Channels::Gray,
        ("<f4", [_, _, 4]) => Channels::Rgba,
        _ => return Err(format!("expected float32 (H, W) or (H, W, 4), got {} {:?}", a.dtype, a.shape)),
    };
    let (w, h) = image_size(&a.shape)?;
    let mut data = vec![0f32; w as usize * h as usize * channels.count()];
    arena.get_into(a.offset, bytemuck::cast_slice_mut(&mut data)).map_err(|e| e.to_string())?;
    Image::from_vec(w, h, channels, data).ok_or_else(|| "the pixel count does not match the shape".into())
}

fn read_mask(arena: &Arena, a: &ArraySpec) -> Result<Mask, String> {
    if a.dtype != "|u1" || a.shape.len() != 2 {
        return Err(format!("expected uint8 (H, W), got {} {:?}", a.dtype, a.shape));
    }
    let (w, h) = image_size(&a.shape)?;
    let mut data = vec![0u8; w as usize * h as usize];
    arena.get_into(a.offset, &mut data).map_err(|e| e.to_string())?;
    Mask::from_vec(w, h, data).ok_or_else(|| "the pixel count does not match the shape".into())
}

/// Points from float64 rows `(x, y, z)` (from time 0) or `(seconds, x, y, z)`.
fn read_points(arena: &Arena, a: &ArraySpec) -> Result<Points, String> {
    let (n, columns) = match (a.dtype.as_str(), a.shape.as_slice()) {
        ("<f8", &[n, c @ (3 | 4)]) => (n, c as usize),
        _ => return Err(format!("expected float64 (N, 3) or (N, 4), got {} {:?}", a.dtype, a.shape)),
    };
    if n == 0 || n > MAX_POINTS {
        return Err(format!("{n} points: a point list holds 1 to {MAX_POINTS}"));
    }
    let mut data = vec![0f64; n as usize * columns];
    arena.get_into(a.offset, bytemuck::cast_slice_mut(&mut data)).map_err(|e| e.to_string())?;
    let points = data
        .chunks_exact(columns)
        .map(|r| match r {
            &[t, x, y, z] => (t, Place::At([x, y, z])),
            r => (0.0, Place::At([r[0], r[1], r[2]])),
        })
        .collect();
    Points::new(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn images_and_masks_go_through_the_arena_unchanged() {
        let arena = Arena::create().unwrap();
        let img = Image::gray_from_fn(5, 3, |x, y| x as f32 + 10.0 * y as f32);
        let spec = put_image(&arena, 64, &img).unwrap();
        assert_eq!((spec.shape.as_slice(), spec.dtype.as_str()), (&[3u64, 5][..], "<f4"));
        assert_eq!(read_image(&arena, &spec).unwrap(), img);
        let rgba = img.to_rgba();
        let spec = put_image(&arena, 0, &rgba).unwrap();
        assert_eq!(spec.shape, [3, 5, 4]);
        assert_eq!(read_image(&arena, &spec).unwrap(), rgba);
    }

    #[test]
    fn wrong_or_absurd_arrays_are_refused_before_allocating() {
        let arena = Arena::create().unwrap();
        let spec = |shape: Vec<u64>, dtype: &str| ArraySpec { offset: 0, shape, dtype: dtype.into() };
        let e = read_image(&arena, &spec(vec![4, 4, 3], "<f4")).unwrap_err();
        assert!(e.contains("expected float32 (H, W) or (H, W, 4), got <f4 [4, 4, 3]"), "{e}");
        let e = read_image(&arena, &spec(vec![1 << 31, 1 << 31], "<f4")).unwrap_err();
        assert!(e.contains("over the pixel limit"), "{e}");
        assert!(read_image(&arena, &spec(vec![0, 4], "<f4")).unwrap_err().contains("empty"));
        let e = read_image(&arena, &spec(vec![8, 8], "<f4")).unwrap_err();
        assert!(e.contains("past the end"), "an output the worker never wrote: {e}");
        assert!(read_mask(&arena, &spec(vec![2, 2], "<f4")).unwrap_err().contains("expected uint8"));
        let e = read_points(&arena, &spec(vec![1 << 40, 4], "<f8")).unwrap_err();
        assert!(e.contains("a point list holds 1 to 16777216"), "{e}");
        assert!(read_points(&arena, &spec(vec![2, 2], "<f8")).unwrap_err().contains("expected float64 (N, 3) or (N, 4)"));
    }

    #[test]
    fn non_finite_parameters_are_refused_before_python() {
        for v in [Value::Float(f64::NAN), Value::Vec3([0.0, f64::INFINITY, 0.0]), Value::Color([0.0, f32::NAN, 0.0, 1.0])] {
            let e = param_json(&v).unwrap_err();
            assert!(e.contains("cannot be passed to a Python plugin"), "{e}");
        }
        assert_eq!(param_json(&Value::Float(1.5)).unwrap(), json!(1.5));
    }

    #[test]
    fn a_ramp_goes_to_python_as_rows_of_position_and_values() {
        let ramp =
            pyrograph_core::value::RampKeys::new(2, vec![(0.0, [1.0, 2.0, 9.0, 9.0]), (0.5, [3.0, 4.0, 9.0, 9.0])]).unwrap();
        assert_eq!(param_json(&Value::Ramp(Arc::new(ramp))).unwrap(), json!([[0.0, 1.0, 2.0], [0.5, 3.0, 4.0]]));
    }

    #[test]
    fn a_mask_read_back_is_zero_or_255() {
        let arena = Arena::create().unwrap();
        arena.put(0, &[0, 1, 255, 7]).unwrap();
        let m = read_mask(&arena, &ArraySpec { offset: 0, shape: vec![2, 2], dtype: "|u1".into() }).unwrap();
        assert_eq!(m.data(), [0, 255, 255, 255]);
    }

    #[test]
    fn point_rows_become_timed_places_and_bad_ones_are_refused() {
        let arena = Arena::create().unwrap();
        let rows: [f64; 8] = [0.5, 1.0, 2.0, 3.0, 0.0, -1.0, 0.0, 1.0];
        arena.put(0, bytemuck::cast_slice(&rows)).unwrap();
        let timed = read_points(&arena, &ArraySpec { offset: 0, shape: vec![2, 4], dtype: "<f8".into() }).unwrap();
        let want = Points::new(vec![(0.5, Place::At([1.0, 2.0, 3.0])), (0.0, Place::At([-1.0, 0.0, 1.0]))]).unwrap();
        assert_eq!(timed, want);
        let still = read_points(&arena, &ArraySpec { offset: 0, shape: vec![2, 3], dtype: "<f8".into() }).unwrap();
        let want = Points::new(vec![(0.0, Place::At([0.5, 1.0, 2.0])), (0.0, Place::At([3.0, 0.0, -1.0]))]).unwrap();
        assert_eq!(still, want);
        arena.put(0, bytemuck::cast_slice(&[-1.0f64, 0.0, 0.0, 0.0])).unwrap();
        let e = read_points(&arena, &ArraySpec { offset: 0, shape: vec![1, 4], dtype: "<f8".into() }).unwrap_err();
        assert!(e.contains("point 1: the time must be a number of seconds ≥ 0"), "{e}");
    }
}
