//! Sampling animated parameters: a 10-key smooth channel, a 10-key channel mixing every
//! interpolation, and an expression, each at frames that change every call (in a scrambled order
//! over the keys and both extrapolated ends, so neither the search nor the branches settle).
//! Target: a channel sample ≤ 100 ns. A simulation samples each animated parameter once per step.

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use pyrograph_core::anim::{Channel, Expr, Extrap, Interp, Key};
use pyrograph_core::declare::{Anim, Port};
use pyrograph_core::{PortDesc, Value};

/// 1,024 frames from −5 to 95 (keys span 0..90), fractional and out of order.
fn frames() -> Vec<f64> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    (0..1024)
        .map(|_| {
            // xorshift64: a fixed scramble, the same every run.
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            -5.0 + 100.0 * (state >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

/// Ten keys 10 frames apart with values that rise and fall, each leaving with `interp(i)`.
fn channel(interp: impl Fn(usize) -> Interp) -> Channel {
    let values = [0.2, 1.5, 0.9, 1.1, 2.4, 0.3, 0.3, 1.8, 1.0, 0.6];
    let keys = values.iter().enumerate().map(|(i, &value)| Key { frame: 10.0 * i as f64, value, interp: interp(i) }).collect();
    Channel::new(keys, Extrap::Hold, Extrap::Linear).expect("valid keys")
}

/// Every interpolation in turn.
fn mixed(i: usize) -> Interp {
    match i % 5 {
        0 => Interp::Smooth,
        1 => Interp::Linear,
        2 => Interp::Ease,
        3 => Interp::Tangent { in_slope: 0.05, out_slope: -0.02 },
        _ => Interp::Constant,
    }
}

/// Runs `sample` once per iteration on the next frame of the scrambled list.
fn bench_frames(c: &mut Criterion, name: &str, mut sample: impl FnMut(f64) -> f64) {
    let frames = frames();
    let mut i = 0usize;
    c.bench_function(name, |b| {
        b.iter(|| {
            i = (i + 1) & 1023;
            black_box(sample(black_box(frames[i])))
        })
    });
}

fn anim(c: &mut Criterion) {
    let smooth = channel(|_| Interp::Smooth);
    bench_frames(c, "channel/smooth_10_keys", |f| smooth.sample(f));
    let mixed = channel(mixed);
    bench_frames(c, "channel/mixed_10_keys", |f| mixed.sample(f));
    let expr = Expr::parse("0.5 + 0.2 * sin(time * 3)").expect("parses");
    bench_frames(c, "expr/0.5+0.2*sin(time*3)", |f| expr.eval(f, 24.0).expect("finite"));

    // What a node pays per sample: `Anim::at` on the mixed channel, through the parameter's track,
    // the NaN and range checks and the conversion to the port's type.
    let written = pyrograph_core::ParamValue::parse_cli(
        "keys([(0, 0.2), (10, 1.5, linear), (20, 0.9, ease), (30, 1.1, tangent(0.05, -0.02)), (40, 2.4, constant), \
         (50, 0.3), (60, 0.3, linear), (70, 1.8, ease), (80, 1.0, tangent(0.05, -0.02)), (90, 0.6, constant)], hold, linear)",
    );
    let animated =
        pyrograph_core::value::animated_param(&written, &pyrograph_core::PortType::Float).expect("valid keys").expect("animated");
    let port = PortDesc::float("gain", 0.0, (-10.0, 10.0), "a ranged Float parameter");
    let param = Anim::<f64>::from_port(&Value::Anim(Arc::new(animated)), &port).expect("a Float animation");
    bench_frames(c, "anim_at/mixed_10_keys", |f| param.at(f, 24.0).expect("in range"));
}

criterion_group!(benches, anim);
criterion_main!(benches);
