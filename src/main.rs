fn main() -> std::process::ExitCode {
    quiet_device_select_layer();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    match stereocull::cli::run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("stereocull: {}", e.one_line());
            std::process::ExitCode::FAILURE
        }
    }
}

/// Mesa's implicit Vulkan layer `VK_LAYER_MESA_device_select` connects to Wayland while
/// the adapters are enumerated and, on a machine without a display, prints
/// `error: XDG_RUNTIME_DIR is invalid ...` twice before a run that then succeeds. The
/// layer only reorders adapters, and `stereocull` picks its adapter itself
/// (`device::Gpu`), so the CLI turns the layer off unless the user set its variable.
fn quiet_device_select_layer() {
    const DISABLE: &str = "NODEVICE_SELECT";
    if std::env::var_os(DISABLE).is_none() {
        // SAFETY: called first thing in `main`, before any thread exists that could read
        // the environment concurrently.
        unsafe { std::env::set_var(DISABLE, "1") };
    }
}
