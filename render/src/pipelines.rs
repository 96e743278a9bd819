//! The view pipelines: one per feature set, compiled on first use (or ahead of it) and cached.

use crate::specialize::view_source_for;
use lodestone_core::material::features::FeatureSet;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

/// One compiled view pipeline per feature set. An entry's `OnceLock` is created under the map's
/// lock and filled outside it, so different sets compile concurrently and a second request for
/// a set being compiled waits for that compilation instead of starting another.
#[derive(Debug, Default)]
pub(crate) struct PipelineCache {
    pub(crate) map: Mutex<HashMap<FeatureSet, Arc<OnceLock<Compiled>>>>,
}

/// A compiled pipeline and what it cost.
#[derive(Debug, Clone)]
pub(crate) struct Compiled {
    pub(crate) pipeline: Arc<wgpu::ComputePipeline>,
    pub(crate) took: Duration,
}

impl PipelineCache {
    pub(crate) fn entry(&self, set: FeatureSet) -> Arc<OnceLock<Compiled>> {
        let mut map = self.map.lock().unwrap_or_else(|e| e.into_inner());
        map.entry(set).or_default().clone()
    }

    pub(crate) fn get(&self, device: &wgpu::Device, set: FeatureSet) -> Compiled {
        self.entry(set).get_or_init(|| compile(device, set)).clone()
    }

    pub(crate) fn ready(&self, set: FeatureSet) -> bool {
        let map = self.map.lock().unwrap_or_else(|e| e.into_inner());
        map.get(&set).is_some_and(|e| e.get().is_some())
    }
}

pub(crate) fn compile(device: &wgpu::Device, set: FeatureSet) -> Compiled {
    let t0 = Instant::now();
    // The shipped sources are checked for every feature set by a test; failing here is a bug.
    let source = view_source_for(set).expect("the view shader specialises for every feature set");
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("view"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("view"),
        layout: None,
        module: &module,
        entry_point: Some("view_main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let took = t0.elapsed();
    log::info!("view pipeline [{set}] compiled in {took:.1?}");
    Compiled {
        pipeline: Arc::new(pipeline),
        took,
    }
}
