//! ArduCopter SITL for `hubtrack fly --autopilot ardupilot`: a private loopback-only network,
//! and one fresh firmware process per flight.
//!
//! SITL binds its TCP and UDP ports on every interface (0.0.0.0) and has no option to change
//! that, so the whole flight — SITL, the stages, their MAVLink links and the JSON physics port —
//! runs in a network namespace of its own that has only the loopback interface: `hubtrack fly`
//! re-runs itself under `unshare -n` (root, or CAP_SYS_ADMIN) before anything starts. Inside,
//! the ports are private to the flight, so parallel runs never collide.

use anyhow::{bail, Context};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

/// Set in the re-run `hubtrack fly` inside its private network namespace.
const NETNS_ENV: &str = "HUBTRACK_FLY_NETNS";
/// Where the SITL binary and ArduPilot's default parameters are looked for when neither
/// `--ardupilot-dir` nor `HUBTRACK_ARDUPILOT_DIR` says.
pub const DEFAULT_DIR: &str = "../shared/tools/ardupilot";
/// The SITL binary in that folder.
const BINARY: &str = "arducopter";
/// ArduPilot's own default parameters for a quad (`Tools/autotest/default_params/copter.parm`).
const DEFAULT_PARAMS: &str = "copter.parm";
/// SITL's home: latitude, longitude (deg), altitude (m AMSL), heading (deg). Where on earth does
/// not matter to the approach; a fixed home keeps the firmware's world (magnetic field, GPS)
/// the same for every flight.
const HOME: &str = "63.4,10.4,50,0";
/// The repository's parameters for the flights (`config/ardupilot/sitl.parm`), built in so
/// that a binary always flies with the parameters it was built with.
pub const PARAMS: &str = include_str!("../../../config/ardupilot/sitl.parm");
/// SITL paces itself to at most this multiple of real time; the physics it is coupled to sets the
/// actual pace (the lockstep), so this only has to be out of the way.
const SPEEDUP: &str = "1000";

/// The folder holding `arducopter` and `copter.parm`: `dir` if given, else
/// `HUBTRACK_ARDUPILOT_DIR`, else [`DEFAULT_DIR`]; an error naming what is missing.
pub fn locate(dir: Option<&Path>) -> anyhow::Result<PathBuf> {
    let dir = dir
        .map(Path::to_path_buf)
        .or_else(|| std::env::var_os("HUBTRACK_ARDUPILOT_DIR").map(PathBuf::from))
        .unwrap_or_else(|| PathBuf::from(DEFAULT_DIR));
    for file in [BINARY, DEFAULT_PARAMS] {
        if !dir.join(file).is_file() {
            bail!(
                "ArduCopter SITL not found: {} is missing (give the folder with --ardupilot-dir or HUBTRACK_ARDUPILOT_DIR)",
                dir.join(file).display()
            );
        }
    }
    dir.canonicalize()
        .with_context(|| format!("resolving {}", dir.display()))
}

/// Inside the private network namespace already (this process was re-run there).
pub fn in_private_network() -> bool {
    std::env::var_os(NETNS_ENV).is_some()
}

/// Re-runs this command inside a new network namespace with only loopback up, waits for it and
/// returns its exit code. SIGINT/SIGTERM to this process are passed on (as SIGTERM), so the
/// flights inside stop cleanly and take their SITL with them.
pub fn rerun_in_private_network() -> anyhow::Result<i32> {
    let shutdown = hubtrack_runtime::shutdown::Shutdown::install()?;
    let exe = std::env::current_exe().context("finding the hubtrack executable")?;
    // `unshare` execs the command after entering the namespace: the child is `hubtrack fly`.
    let mut child = Command::new("unshare")
        .arg("-n")
        .arg("--")
        .arg(&exe)
        .args(std::env::args_os().skip(1))
        .env(NETNS_ENV, "1")
        .spawn()
        .context("running `unshare -n` (util-linux) for a private network")?;
    let mut forwarded = false;
    loop {
        if let Some(status) = child.try_wait()? {
            return match status.code() {
                Some(code) => Ok(code),
                None => bail!("hubtrack fly in its private network ended by a signal ({status})"),
            };
        }
        if shutdown.requested() && !forwarded {
            forwarded = true;
            let _ = Command::new("kill")
                .args(["-TERM", &child.id().to_string()])
                .status();
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
}

/// Brings the loopback interface of the new namespace up.
pub fn loopback_up() -> anyhow::Result<()> {
    let status = Command::new("ip")
        .args(["link", "set", "lo", "up"])
        .status()
        .context("running `ip link set lo up` (iproute2)")?;
    if !status.success() {
        bail!("`ip link set lo up` failed ({status}): a private network needs root or CAP_SYS_ADMIN (`unshare -n`)");
    }
    Ok(())
}

/// One running SITL; killed when dropped.
pub struct Sitl {
    child: Child,
    log: PathBuf,
}

/// The ports one flight's SITL talks on.
#[derive(Debug, Clone, Copy)]
pub struct SitlPorts {
    /// SERIAL0, to control's `udpin` link.
    pub control: u16,
    /// SERIAL1, to the simulator's pilot (`udpin`).
    pub pilot: u16,
}

impl Sitl {
    /// Starts `arducopter` from `dir` in the empty folder `run_dir` with ArduPilot's default
    /// parameters and then [`PARAMS`], its EEPROM wiped (every flight starts from the same
    /// parameters), the JSON physics model and MAVLink on `ports`.
    pub fn start(dir: &Path, run_dir: &Path, ports: SitlPorts) -> anyhow::Result<Sitl> {
        std::fs::create_dir_all(run_dir)
            .with_context(|| format!("creating {}", run_dir.display()))?;
        let params = run_dir.join("hubtrack-sitl.parm");
        std::fs::write(&params, PARAMS).with_context(|| format!("writing {}", params.display()))?;
        let log = run_dir.join("arducopter.log");
        let out =
            std::fs::File::create(&log).with_context(|| format!("creating {}", log.display()))?;
        let defaults = format!(
            "{},{}",
            dir.join(DEFAULT_PARAMS).display(),
            params.display()
        );
        let child = Command::new(dir.join(BINARY))
            .current_dir(run_dir)
            .args([
                "--model",
                "JSON:127.0.0.1",
                "--speedup",
                SPEEDUP,
                "-I0",
                "-w",
            ])
            .args(["--home", HOME, "--defaults", &defaults])
            .args([
                "--serial0",
                &format!("udpclient:127.0.0.1:{}", ports.control),
            ])
            .args(["--serial1", &format!("udpclient:127.0.0.1:{}", ports.pilot)])
            .stdin(Stdio::null())
            .stdout(out.try_clone()?)
            .stderr(out)
            .spawn()
            .with_context(|| format!("starting {}", dir.join(BINARY).display()))?;
        log::info!(
            "ArduCopter SITL pid {} in {} (control on UDP {}, pilot on UDP {})",
            child.id(),
            run_dir.display(),
            ports.control,
            ports.pilot
        );
        Ok(Sitl { child, log })
    }

    /// The last lines SITL printed, for an error message.
    pub fn log_tail(&self) -> String {
        let text = std::fs::read_to_string(&self.log).unwrap_or_default();
        let lines: Vec<&str> = text.lines().collect();
        lines[lines.len().saturating_sub(15)..].join("\n")
    }

    /// Whether SITL is still running.
    pub fn running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }
}

impl Drop for Sitl {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
