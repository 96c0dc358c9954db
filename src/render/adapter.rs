//! Whether this machine can render: asks for a GPU adapter exactly as Bevy's `RenderPlugin` will (the same
//! settings, read from the same environment variables such as `WGPU_BACKEND`), with the panic Bevy raises when
//! there is none caught and kept quiet. `play` asks before it opens a window; the GPU test harness asks before
//! it runs.

use bevy::render::renderer::initialize_renderer;
use bevy::render::settings::WgpuSettings;

/// The adapter Bevy will render with: its name and backend, and the largest storage buffer it binds.
pub struct Adapter {
    pub name: String,
    pub max_binding: u64,
}

/// The adapter, or why there is none.
pub fn probe_adapter() -> Result<Adapter, String> {
    let settings = WgpuSettings::default();
    let Some(backends) = settings.backends else { return Err("no wgpu backend enabled".into()) };
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let found = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        bevy::tasks::block_on(initialize_renderer(backends, None, &settings))
    }));
    std::panic::set_hook(hook);
    match found {
        Ok(resources) => Ok(Adapter {
            name: format!("{} ({:?})", resources.2.name, resources.2.backend),
            max_binding: resources.0.limits().max_storage_buffer_binding_size,
        }),
        Err(panic) => Err(panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "the renderer could not start".into())),
    }
}

/// The adapter's name and backend for a report, or "an unknown adapter" when there is none.
pub fn adapter_name() -> String {
    probe_adapter().map_or_else(|_| "an unknown adapter".into(), |adapter| adapter.name)
}
