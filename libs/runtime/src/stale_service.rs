//! Recovery from services left half-created by a killed process (iceoryx2 `HangsInCreation`).
//!
//! iceoryx2 0.10 creates a service's static config file with the permissions `0600` ("being
//! set up"), writes it, then makes it read-only (`0400`). A process killed between the two leaves
//! a `0600` file behind for good: every later `open_or_create` waits for the creation to finish
//! and fails with `HangsInCreation`, and the dead-node cleanup does not remove it (it only
//! removes services whose static config is complete; a dead creator that got further, with the
//! static config complete but no dynamic config, is removed as corrupted by that cleanup). In a
//! kill storm this left stages unable to start (308 errors).
//!
//! So when opening fails with `HangsInCreation`, the dead nodes are cleaned up, and a static
//! config of the service still "being set up" after iceoryx2's own creation timeout is removed;
//! then opening is tried again after a bounded back-off.

use crate::ipc::Ipc;
use iceoryx2::prelude::*;
use iceoryx2::service::messaging_pattern::MessagingPattern;
use iceoryx2::service::service_hash::ServiceHash;
use iceoryx2::service::Service;
use std::fmt::Debug;
use std::os::unix::fs::PermissionsExt;
use std::path::PathBuf;
use std::time::{Duration, SystemTime};

/// Attempts after the first `HangsInCreation` before the error is given up on.
const RETRIES: u32 = 4;
/// First back-off between attempts; doubled each time (10 + 20 + 40 + 80 ms at most, on top of
/// iceoryx2's own wait of its creation timeout per attempt).
const FIRST_BACKOFF: Duration = Duration::from_millis(10);
/// The permission bits iceoryx2 gives a static config while it is being written.
const IN_CREATION_MODE: u32 = 0o600;

/// True when an iceoryx2 open-or-create error says the service hangs in creation. The error
/// types differ per messaging pattern and nest the cause (e.g.
/// `EventOpenOrCreateError::EventOpenError(EventOpenError::HangsInCreation)`); all name it so.
fn hangs_in_creation(e: &impl Debug) -> bool {
    format!("{e:?}").contains("HangsInCreation")
}

/// Where iceoryx2 keeps the static config of service `name` with `pattern`.
pub(crate) fn static_config_path(
    node: &Node<Ipc>,
    name: &ServiceName,
    pattern: MessagingPattern,
) -> PathBuf {
    let global = &node.config().global;
    let hash = ServiceHash::new::<<Ipc as Service>::ServiceNameHasher>(name, pattern);
    PathBuf::from(global.service_dir().to_string()).join(format!(
        "{}{}{}",
        global.prefix,
        hash.as_str(),
        global.service.static_config_storage_suffix
    ))
}

/// Removes the service's static config if it is still "being set up" and older than iceoryx2's
/// creation timeout (its creator is gone: creating takes microseconds). Returns whether it did.
fn remove_if_stuck(node: &Node<Ipc>, name: &ServiceName, pattern: MessagingPattern) -> bool {
    let path = static_config_path(node, name, pattern);
    let Ok(meta) = std::fs::metadata(&path) else {
        return false;
    };
    let age = meta
        .modified()
        .ok()
        .and_then(|t| SystemTime::now().duration_since(t).ok())
        .unwrap_or_default();
    let stuck = meta.permissions().mode() & 0o777 == IN_CREATION_MODE
        && age > node.config().global.creation_timeout;
    if !stuck {
        return false;
    }
    match std::fs::remove_file(&path) {
        Ok(()) => {
            log::warn!(
                "iceoryx2 service `{name}` was left half-created ({} s ago, by a process killed while creating it): removed {}",
                age.as_secs(),
                path.display()
            );
            true
        }
        Err(e) => {
            log::warn!(
                "iceoryx2 service `{name}` hangs in creation; cannot remove {}: {e}",
                path.display()
            );
            false
        }
    }
}

/// Runs `open` (an `open_or_create` of service `name`); on `HangsInCreation` cleans up dead
/// nodes and a stuck static config and tries again, at most [`RETRIES`] more times.
pub(crate) fn open_or_create_recovering<T, E: Debug>(
    node: &Node<Ipc>,
    name: &ServiceName,
    pattern: MessagingPattern,
    mut open: impl FnMut() -> Result<T, E>,
) -> Result<T, E> {
    let mut backoff = FIRST_BACKOFF;
    let mut attempt = 0;
    loop {
        match open() {
            Err(e) if hangs_in_creation(&e) && attempt < RETRIES => {
                attempt += 1;
                let cleaned = node.try_cleanup_dead_nodes();
                let removed = remove_if_stuck(node, name, pattern);
                log::info!(
                    "iceoryx2 service `{name}` hangs in creation (attempt {attempt}): {} dead node(s) cleaned up, stuck static config {}; retrying in {} ms",
                    cleaned.cleanups,
                    if removed { "removed" } else { "not found" },
                    backoff.as_millis()
                );
                std::thread::sleep(backoff);
                backoff *= 2;
            }
            other => return other,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ipc::{open_node, scoped_name, MsgPublisher, MsgSubscriber, DOMAIN_ENV};
    use hubtrack_types::services::VEHICLE;
    use hubtrack_types::VehicleState;

    /// A static config file left at `0600` (its creator killed between writing it and making it
    /// read-only), as found in /tmp/iceoryx2/services after kill storms: opening recovers.
    #[test]
    fn a_service_left_half_created_by_a_killed_process_is_recovered() {
        // The only test in this crate that sets the domain; the name is unique per run.
        let domain = format!(
            "stale-{}-{}",
            std::process::id(),
            hubtrack_types::time::monotonic_ns()
        );
        std::env::set_var(DOMAIN_ENV, &domain);
        let node = open_node("stale-test").unwrap();
        let name: ServiceName = scoped_name(VEHICLE.name).as_str().try_into().unwrap();
        let path = static_config_path(&node, &name, MessagingPattern::PublishSubscribe);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        {
            use std::os::unix::fs::OpenOptionsExt;
            let f = std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .mode(IN_CREATION_MODE)
                .open(&path)
                .unwrap();
            // Older than the creation timeout, as after a kill.
            f.set_modified(SystemTime::now() - Duration::from_secs(60))
                .unwrap();
        }
        let publisher = MsgPublisher::<VehicleState>::new(&node, &VEHICLE)
            .expect("the half-created service is recovered");
        let subscriber = MsgSubscriber::<VehicleState>::polling(&node, &VEHICLE, 4).unwrap();
        publisher.publish(VehicleState::default()).unwrap();
        assert!(subscriber.receive().unwrap().is_some());
        // The service's static config is now complete (read-only).
        let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o400);
    }

    #[test]
    fn only_hangs_in_creation_is_retried() {
        #[derive(Debug)]
        #[allow(dead_code)]
        enum E {
            Open(Inner),
        }
        #[derive(Debug)]
        enum Inner {
            HangsInCreation,
            DoesNotExist,
        }
        assert!(hangs_in_creation(&E::Open(Inner::HangsInCreation)));
        assert!(!hangs_in_creation(&E::Open(Inner::DoesNotExist)));
    }
}
