//! The native viewer: `bvseg-viewer [--run] [--bv KINDS] [MESH]`.
//!
//! Without `MESH`, the bundled bunny is shown. `--run` starts a run with the default settings
//! right away and prints its summary (JSON) on stdout when it ends. `--bv` sets the kinds of
//! volume to start with, as the CLI's `--bv` (`obb,capsule`, `mixed`) or `--target` (`parry`,
//! `mujoco-hull`) take them. A mesh that cannot be read, or kinds that do not parse, are a
//! one-line error (naming the file), with exit status 2, before any window opens.

#[cfg(not(target_arch = "wasm32"))]
fn main() -> std::process::ExitCode {
    native::main()
}

// The browser build enters through the library's `start`.
#[cfg(target_arch = "wasm32")]
fn main() {}

#[cfg(not(target_arch = "wasm32"))]
mod native {
    use std::path::Path;
    use std::process::ExitCode;

    use bvseg_viewer::app::{StartMesh, StartOptions, ViewerApp};
    use bvseg_viewer::platform::Report;
    use bvseg_viewer::{kinds, load_mesh_bytes, meshes};

    const USAGE: &str = "usage: bvseg-viewer [--run] [--bv KINDS] [MESH]\n\n\
        Shows MESH (.obj, .gltf, .glb or .stl), or the bundled bunny, and segments it interactively.\n\
        --run       start a run right away and print its summary on stdout\n\
        --bv KINDS  the kinds of volume to start with: a comma list of ellipsoid, obb, sphere,\n\
        \x20           capsule, cylinder, hull (or mixed), or a target (mujoco, gltf, parry,\n\
        \x20           physx, usd, primitives; NAME-hull adds hulls)";

    fn load(path: &str) -> Result<StartMesh, String> {
        let name = Path::new(path)
            .file_name()
            .map_or_else(|| path.to_string(), |n| n.to_string_lossy().into_owned());
        let bytes = std::fs::read(path).map_err(|e| format!("{path}: cannot read: {e}"))?;
        // Errors name the path given, not just the file name.
        let file = load_mesh_bytes(&bytes, &name).map_err(|e| e.replacen(&name, path, 1))?;
        for w in &file.warnings {
            eprintln!("bvseg-viewer: warning: {path}: {w}");
        }
        Ok(StartMesh::Loaded {
            name,
            mesh: file.mesh,
            warnings: file.warnings,
            animations: file.animations,
        })
    }

    pub fn main() -> ExitCode {
        let mut autorun = false;
        let mut mesh = None;
        let mut bv = None;
        let mut args = std::env::args().skip(1);
        while let Some(arg) = args.next() {
            match arg.as_str() {
                "-h" | "--help" => {
                    println!("{USAGE}");
                    return ExitCode::SUCCESS;
                }
                "--run" => autorun = true,
                "--bv" => match args.next() {
                    Some(v) => bv = Some(v),
                    None => {
                        eprintln!("bvseg-viewer: error: --bv needs a value (see --help)");
                        return ExitCode::from(2);
                    }
                },
                a if a.starts_with("--bv=") => bv = Some(a["--bv=".len()..].to_string()),
                a if a.starts_with('-') => {
                    eprintln!("bvseg-viewer: error: unknown option {a} (see --help)");
                    return ExitCode::from(2);
                }
                a if mesh.is_none() => mesh = Some(a.to_string()),
                a => {
                    eprintln!("bvseg-viewer: error: unexpected argument {a} (one mesh at most)");
                    return ExitCode::from(2);
                }
            }
        }
        if let Some(Err(e)) = bv.as_deref().map(kinds::parse_kinds) {
            eprintln!("bvseg-viewer: error: --bv: {e}");
            return ExitCode::from(2);
        }
        let start_mesh = match mesh {
            Some(p) => match load(&p) {
                Ok(m) => m,
                Err(e) => {
                    eprintln!("bvseg-viewer: error: {e}");
                    return ExitCode::from(2);
                }
            },
            None => StartMesh::Bundled(meshes::BUNDLED[0].name.to_string()),
        };
        let start = StartOptions {
            mesh: start_mesh,
            autorun,
            kinds: bv,
            reporter: Some(Box::new(|r: &Report| match r {
                Report::Done(json) => println!("{json}"),
                Report::Error(e) => eprintln!("bvseg-viewer: error: {e}"),
            })),
            software_renderer: false,
            warm_up: false,
        };
        let options = eframe::NativeOptions {
            viewport: eframe::egui::ViewportBuilder::default()
                .with_title("bvseg viewer")
                .with_inner_size([1280.0, 800.0])
                .with_drag_and_drop(true),
            // The 3D view is depth-tested.
            depth_buffer: 24,
            // X11 (XWayland in a Wayland session), as the glow backend is built for: winit also
            // has its Wayland backend (egui-winit's accesskit turns it on) and would prefer it.
            #[cfg(any(
                target_os = "linux",
                target_os = "dragonfly",
                target_os = "freebsd",
                target_os = "netbsd",
                target_os = "openbsd"
            ))]
            event_loop_builder: Some(Box::new(|builder| {
                winit::platform::x11::EventLoopBuilderExtX11::with_x11(builder);
            })),
            ..Default::default()
        };
        let result = eframe::run_native(
            "bvseg viewer",
            options,
            Box::new(move |_cc| Ok(Box::new(ViewerApp::new(start)))),
        );
        match result {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("bvseg-viewer: error: cannot open the window: {e}");
                ExitCode::FAILURE
            }
        }
    }
}
