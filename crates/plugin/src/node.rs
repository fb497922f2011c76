//! A node type declared in Python: described like a built-in, cooked by sending its inputs to a
//! worker (numbers as JSON, pixels through the arena) and reading its outputs back checked.

use std::sync::Arc;

use pyrograph_core::value::PortType;
use pyrograph_core::{Channels, CookCtx, Image, Inputs, Mask, Node, NodeDesc, NodeError, Value};
use serde_json::{Map, Value as Json, json};

use crate::arena::{Arena, aligned};
use crate::discover::PluginFile;
use crate::pool::Pool;
use crate::protocol::{ArraySpec, OutputSpec, Reply};
use crate::worker::{Worker, WorkerError};

/// A plugin node type.
pub struct PyNode {
    /// Its description, from the declaration.
    pub desc: NodeDesc,
    /// The file that declares it.
    pub file: Arc<PluginFile>,
    /// For each input, the channels an image must have (`gray`, `rgba`), if the plugin says.
    pub channels: Vec<Option<String>>,
    /// The workers that cook it.
    pub pool: Arc<Pool>,
    /// The file's and the host's hashes with the type name: a changed plugin re-cooks.
    pub salt: u64,
}

impl Node for PyNode {
    fn desc(&self) -> &NodeDesc {
        &self.desc
    }

    fn fingerprint_salt(&self) -> u64 {
        self.salt
    }

    fn cook(&self, inputs: &Inputs<'_>, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
        let outcome = self.pool.with_worker(Some(ctx), |worker| Ok(self.cook_on(worker, inputs.values(), ctx)));
        match outcome {
            Ok(result) => result,
            Err(WorkerError::Cancelled) => Err(NodeError::Cancelled),
            Err(WorkerError::Broken(why)) => Err(NodeError::Message(format!("{why} (plugin {})", self.file.path.display()))),
        }
    }
}

impl PyNode {
    /// One cook on one worker: inputs in, request, outputs back.
    fn cook_on(&self, worker: &mut Worker, values: &[Value], ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
        let mut params = Map::new();
        let mut arrays = Map::new();
        let mut offset = 0u64;
        for ((port, value), channels) in self.desc.inputs.iter().zip(values).zip(&self.channels) {
            pyrograph_core::declare::check_range(port, value).map_err(|e| NodeError::port(&port.name, e))?;
            match value {
                Value::Image(img) => {
                    check_channels(img, channels.as_deref()).map_err(|e| NodeError::port(&port.name, e))?;
                    let spec = put_image(&worker.arena, offset, img).map_err(|e| arena_error(&port.name, e))?;
                    offset = aligned(spec.offset + (img.data().len() * 4) as u64);
                    arrays.insert(port.name.clone(), json!(spec));
                }
                Value::Mask(mask) => {
                    worker.arena.put(offset, mask.data()).map_err(|e| arena_error(&port.name, e))?;
                    let spec = ArraySpec { offset, shape: vec![mask.height().into(), mask.width().into()], dtype: "|u1".into() };
                    offset = aligned(offset + mask.data().len() as u64);
                    arrays.insert(port.name.clone(), json!(spec));
                }
                other => {
                    params.insert(port.name.clone(), param_json(other).map_err(|e| NodeError::port(&port.name, e))?);
                }
            }
        }
        let request = json!({
            "op": "cook", "id": 1, "type": self.desc.type_name, "file": self.file.path, "sha256": self.file.sha256,
            "frame": Json::Null, "params": params, "arrays": arrays, "out_offset": offset,
        });
        match worker.request(&request, Some(ctx)) {
            Ok(Reply::Result { outputs, .. }) => self.read_outputs(&worker.arena, &outputs),
            Ok(Reply::Error(failure)) => Err(match failure.kind.as_str() {
                "cancelled" => NodeError::Cancelled,
                "port" => NodeError::Message(failure.error.message),
                _ => NodeError::Message(failure.error.render()),
            }),
            Ok(other) => Err(NodeError::Message(format!("the Python worker answered a cook with {other:?}"))),
            Err(WorkerError::Cancelled) => Err(NodeError::Cancelled),
            Err(WorkerError::Broken(why)) => Err(NodeError::Message(format!("{why} (plugin {})", self.file.path.display()))),
        }
    }

    /// The outputs in declared order, each checked against its declared type.
    fn read_outputs(&self, arena: &Arena, outputs: &[OutputSpec]) -> Result<Vec<Value>, NodeError> {
        self.desc
            .outputs
            .iter()
            .map(|port| {
                let out = outputs.iter().find(|o| o.port == port.name);
                let out =
                    out.ok_or_else(|| NodeError::Message(format!("output '{}': the plugin returned nothing for it", port.name)))?;
                read_output(arena, &port.ty, out).map_err(|e| NodeError::Message(format!("output '{}': {e}", port.name)))
            })
            .collect()
    }
}

fn arena_error(port: &str, e: std::io::Error) -> NodeError {
    NodeError::port(port, format!("could not pass the pixels to Python: {e}"))
}

fn check_channels(img: &Image, wanted: Option<&str>) -> Result<(), String> {
    match (wanted, img.channels()) {
        (Some("gray"), Channels::Rgba) => Err("the plugin takes gray images; convert with imaging.to_gray first".into()),
        (Some("rgba"), Channels::Gray) => Err("the plugin takes RGBA images; this one is gray".into()),
        _ => Ok(()),
    }
}

fn put_image(arena: &Arena, offset: u64, img: &Image) -> std::io::Result<ArraySpec> {
    arena.put(offset, bytemuck::cast_slice(img.data()))?;
    let mut shape = vec![u64::from(img.height()), u64::from(img.width())];
    if img.channels() == Channels::Rgba {
        shape.push(4);
    }
    Ok(ArraySpec { offset, shape, dtype: "<f4".into() })
}

/// A parameter as the plugin function receives it (colours and vectors as lists).
fn param_json(v: &Value) -> Result<Json, String> {
    Ok(match v {
        Value::Float(x) => json!(x),
        Value::Int(i) => json!(i),
        Value::Bool(b) => json!(b),
        Value::String(s) | Value::Enum(s) => json!(s),
        Value::Color(c) => json!(c),
        Value::Vec2(v) => json!(v),
        Value::Vec3(v) => json!(v),
        Value::Path(p) => json!(p.to_str().ok_or_else(|| format!("path {} is not valid UTF-8", p.display()))?),
        other => return Err(format!("a plugin cannot take a {} here", other.type_name())),
    })
}

/// One output value: an array read from the arena, or a number.
fn read_output(arena: &Arena, ty: &PortType, out: &OutputSpec) -> Result<Value, String> {
    match (ty, &out.array, &out.value) {
        (PortType::Image, Some(a), _) => read_image(arena, a).map(|i| Value::Image(Arc::new(i))),
        (PortType::Mask, Some(a), _) => read_mask(arena, a).map(|m| Value::Mask(Arc::new(m))),
        (PortType::Float, _, Some(j)) => j.as_f64().map(Value::Float).ok_or(format!("{j} is not a number")),
        (PortType::Int, _, Some(j)) => j.as_i64().map(Value::Int).ok_or(format!("{j} is not an integer")),
        (PortType::Bool, _, Some(j)) => j.as_bool().map(Value::Bool).ok_or(format!("{j} is not true or false")),
        _ => Err(format!("the plugin returned something that is not a {}", ty)),
    }
}

/// Width and height of a `(H, W)` or `(H, W, C)` array, refused before allocating when the image
/// would be over the pixel limit.
fn image_size(shape: &[u64]) -> Result<(u32, u32), String> {
    let (h, w) = (shape[0], shape[1]);
    let limit = pyrograph_core::limits::max_pixels();
    if h == 0 || w == 0 || h.saturating_mul(w) > limit {
        let hint = pyrograph_core::limits::raise_hint("--max-pixels", "PYROGRAPH_MAX_PIXELS", limit);
        return Err(format!("a {w} × {h} image is empty or over the pixel limit ({hint})"));
    }
    Ok((w as u32, h as u32))
}

fn read_image(arena: &Arena, a: &ArraySpec) -> Result<Image, String> {
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
    }

    #[test]
    fn a_mask_read_back_is_zero_or_255() {
        let arena = Arena::create().unwrap();
        arena.put(0, &[0, 1, 255, 7]).unwrap();
        let m = read_mask(&arena, &ArraySpec { offset: 0, shape: vec![2, 2], dtype: "|u1".into() }).unwrap();
        assert_eq!(m.data(), [0, 255, 255, 255]);
    }
}
