// Mirror of `core/src/eval/query.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

struct FootprintStats {
    driver: FilteredDriver,
    transfer: TransferMoments,
    stats: SurfaceStats,
}

fn footprint_stats(x0: vec2<f32>, fp: vec3<f32>) -> FootprintStats {
    var loc: FootprintStats;
    loc.driver = filtered_driver(x0, fp);
    loc.transfer = transfer_moments(loc.driver.mean, loc.driver.std_dev);
    loc.stats = transformed_statistics(loc.transfer, params.sigma_h, loc.driver.mean_gradient, loc.driver.gradient_cov);
    return loc;
}

fn lit(wi: vec3<f32>, n: vec3<f32>) -> f32 {
    return select(0.0, 1.0, wi.z > 0.0 && dot(n, wi) > 0.0);
}
