//! Table-building benchmarks: the work an edit of a colour map or transfer function triggers.
//! Goal: under 2 ms each so edits stay live. Run with `cargo bench -p lodestone-core`.

use criterion::{Criterion, criterion_group, criterion_main};
use lodestone_core::material::colormap::Gradient;
use lodestone_core::math::preconvolved::TableSpec;
use lodestone_core::microfacet::effective_height::EffectiveHeightTable;
use lodestone_core::microfacet::transfer::{Curve, TransferFunction};
use std::hint::black_box;

fn tables(c: &mut Criterion) {
    let spec = TableSpec::default();
    let viridis = Gradient::viridis(-2.0, 2.0);
    c.bench_function("colormap 256x256 (viridis, 10 stops)", |b| {
        b.iter(|| black_box(viridis.preconvolve(spec)))
    });
    let rust = Gradient::rust(-2.0, 2.0);
    c.bench_function("colormap 256x256 (rust, 4 stops, smooth)", |b| {
        b.iter(|| black_box(rust.preconvolve(spec)))
    });
    let moss = TransferFunction::Curve(Curve::moss());
    c.bench_function("transfer g,g²,g′,g′² 256x256 (moss)", |b| {
        b.iter(|| black_box(moss.preconvolve(spec)))
    });
    let mut g = c.benchmark_group("slow");
    g.sample_size(10);
    g.bench_function("effective height table 1024", |b| {
        b.iter(|| {
            black_box(EffectiveHeightTable::new(
                1e-6,
                1e12,
                EffectiveHeightTable::DEFAULT_SIZE,
            ))
        })
    });
    g.finish();
}

criterion_group!(benches, tables);
criterion_main!(benches);
