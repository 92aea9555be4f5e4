//! iceoryx2 ports for the services in [`hubtrack_types::services`].
//!
//! Every publisher has a companion event notifier so subscribers sleep in the kernel until data
//! arrives (no polling, no added latency). Services are opened with the QoS from `shared-types`,
//! identical in every process.

use crate::stale_service::open_or_create_recovering;
use hubtrack_types::services::{ServiceSpec, FRAMES};
use hubtrack_types::FrameHeader;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use iceoryx2::service::messaging_pattern::MessagingPattern;
use std::fmt::Debug;
use std::time::Duration;

/// The iceoryx2 service flavour used between processes.
pub type Ipc = ipc::Service;

/// A received frame: `[u8]` pixels in shared memory with its [`FrameHeader`].
pub type FrameSample = Sample<Ipc, [u8], FrameHeader>;

/// Why an iceoryx2 port could not be opened or used.
#[derive(Debug, thiserror::Error)]
pub enum IpcError {
    /// Creating the node failed.
    #[error("cannot create iceoryx2 node `{node}`: {reason}")]
    Node {
        /// Node name.
        node: String,
        /// iceoryx2's reason.
        reason: String,
    },
    /// The IPC domain cannot prefix a service's name.
    #[error(
        "{DOMAIN_ENV}={domain:?} cannot prefix the iceoryx2 service name `{service}`: {reason} (a domain is a short name such as `bench1`)"
    )]
    Domain {
        /// The domain as set.
        domain: String,
        /// The service name it prefixes.
        service: String,
        /// iceoryx2's reason.
        reason: String,
    },
    /// Opening a service or creating a port failed.
    #[error("cannot open iceoryx2 service `{service}`: {reason}")]
    Service {
        /// Service name.
        service: String,
        /// iceoryx2's reason.
        reason: String,
    },
    /// Loaning, sending or receiving failed.
    #[error("iceoryx2 {op} on `{service}` failed: {reason}")]
    Transfer {
        /// What was attempted.
        op: &'static str,
        /// Service name.
        service: String,
        /// iceoryx2's reason.
        reason: String,
    },
}

/// Environment variable naming the IPC domain: processes see each other only within one domain
/// (like `ROS_DOMAIN_ID`), so tests and a live pipeline on one machine never mix.
pub const DOMAIN_ENV: &str = "HUBTRACK_DOMAIN";

/// The iceoryx2 service name of `name` in the current domain.
pub fn scoped_name(name: &str) -> String {
    match std::env::var(DOMAIN_ENV) {
        Ok(d) if !d.is_empty() => format!("{d}/{name}"),
        _ => name.to_string(),
    }
}

/// The iceoryx2 name of `name` (one of `spec`'s) in the current domain; a domain that makes
/// it no valid service name (too long, a character iceoryx2 refuses) is named as the cause.
fn service_name(spec: &ServiceSpec, name: &str) -> Result<ServiceName, IpcError> {
    let scoped = scoped_name(name);
    ServiceName::new(scoped.as_str()).map_err(|e| match std::env::var(DOMAIN_ENV) {
        Ok(domain) if !domain.is_empty() => IpcError::Domain {
            domain,
            service: name.into(),
            reason: format!("{e:?}"),
        },
        _ => svc_err(spec, e),
    })
}

fn svc_err(spec: &ServiceSpec, e: impl Debug) -> IpcError {
    IpcError::Service {
        service: spec.name.into(),
        reason: format!("{e:?}"),
    }
}

fn xfer_err(op: &'static str, spec: &ServiceSpec, e: impl Debug) -> IpcError {
    IpcError::Transfer {
        op,
        service: spec.name.into(),
        reason: format!("{e:?}"),
    }
}

/// Opens this process's iceoryx2 node and removes stale resources of dead nodes (a stage that was
/// killed leaves its ports behind; design rule 6). Signal handling stays with [`crate::shutdown`].
pub fn open_node(stage: &str) -> Result<Node<Ipc>, IpcError> {
    let err = |e: &dyn Debug| IpcError::Node {
        node: stage.into(),
        reason: format!("{e:?}"),
    };
    let name: NodeName = stage.try_into().map_err(|e| err(&e))?;
    let node = NodeBuilder::new()
        .name(&name)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<Ipc>()
        .map_err(|e| err(&e))?;
    let cleaned = node.try_cleanup_dead_nodes();
    if cleaned.cleanups > 0 || cleaned.failed_cleanups > 0 {
        log::info!(
            "removed stale iceoryx2 resources of {} dead node(s) ({} could not be cleaned)",
            cleaned.cleanups,
            cleaned.failed_cleanups
        );
    }
    Ok(node)
}

/// Removes resources of dead nodes again (call periodically in long-running publishers so a
/// restarted subscriber finds a free port).
pub fn cleanup_dead_nodes(node: &Node<Ipc>) -> u64 {
    node.try_cleanup_dead_nodes().cleanups
}

fn open_event(node: &Node<Ipc>, spec: &ServiceSpec) -> Result<PortFactoryEvent, IpcError> {
    let name = service_name(spec, spec.event_name)?;
    open_or_create_recovering(node, &name, MessagingPattern::Event, || {
        node.service_builder(&name)
            .event()
            .max_notifiers(spec.qos.max_publishers + 2)
            .max_listeners(spec.qos.max_subscribers + 2)
            .max_nodes(spec.qos.max_nodes)
            .open_or_create()
    })
    .map_err(|e| svc_err(spec, e))
}

type PortFactoryEvent = iceoryx2::service::port_factory::event::PortFactory<Ipc>;

/// Opens or creates the publish-subscribe service of `$spec` with payload `$payload`, the
/// builder passed through `$more` (e.g. a user header), recovering from a service left
/// half-created by a killed process.
macro_rules! open_pubsub {
    ($node:expr, $spec:expr, $payload:ty, |$b:ident| $more:expr) => {{
        let spec: &ServiceSpec = $spec;
        let node: &Node<Ipc> = $node;
        let name = service_name(spec, spec.name)?;
        open_or_create_recovering(node, &name, MessagingPattern::PublishSubscribe, || {
            let $b = node
                .service_builder(&name)
                .publish_subscribe::<$payload>()
                .enable_safe_overflow(spec.qos.safe_overflow)
                .history_size(spec.qos.history_size)
                .subscriber_max_buffer_size(spec.qos.subscriber_max_buffer_size)
                .subscriber_max_borrowed_samples(spec.qos.subscriber_max_borrowed_samples)
                .max_subscribers(spec.qos.max_subscribers)
                .max_publishers(spec.qos.max_publishers)
                .max_nodes(spec.qos.max_nodes);
            $more.open_or_create()
        })
        .map_err(|e| svc_err(spec, e))?
    }};
}

/// Publishes camera frames: pixels are written straight into the loaned shared-memory sample.
pub struct FramePublisher {
    publisher: Publisher<Ipc, [u8], FrameHeader>,
    notifier: Notifier<Ipc>,
}

impl FramePublisher {
    /// Opens the frames service; `initial_max_len` is the expected frame size in bytes (the data
    /// segment grows in powers of two if a larger frame comes).
    pub fn new(node: &Node<Ipc>, initial_max_len: usize) -> Result<FramePublisher, IpcError> {
        let spec = &FRAMES;
        let service = open_pubsub!(node, spec, [u8], |b| b.user_header::<FrameHeader>());
        let publisher = service
            .publisher_builder()
            .initial_max_slice_len(initial_max_len.max(1))
            .allocation_strategy(AllocationStrategy::PowerOfTwo)
            .max_loaned_samples(2)
            .create()
            .map_err(|e| svc_err(spec, e))?;
        let notifier = open_event(node, spec)?
            .notifier_builder()
            .create()
            .map_err(|e| svc_err(spec, e))?;
        Ok(FramePublisher {
            publisher,
            notifier,
        })
    }

    /// Loans `header.sample_len()` bytes of shared memory (the pixels, then the camera's JPEG if
    /// the header announces one), lets `fill` write them (and complete the header, e.g. with
    /// truth known only after rendering), stamps `publish_ns` and sends. Never blocks on
    /// subscribers (safe overflow). If `fill` fails the loan is returned unsent.
    pub fn publish_with<E: From<IpcError>>(
        &self,
        mut header: FrameHeader,
        fill: impl FnOnce(&mut [u8], &mut FrameHeader) -> Result<(), E>,
    ) -> Result<FrameHeader, E> {
        let spec = &FRAMES;
        let len = header.sample_len();
        let mut sample = self
            .publisher
            .loan_slice_uninit(len)
            .map_err(|e| xfer_err("loan", spec, e))?;
        let payload = sample.payload_mut();
        // SAFETY: `u8` has no invalid bit patterns and the chunk lies in mapped shared memory,
        // which the OS initialises (zero pages, or an earlier frame); `fill` only writes.
        let bytes: &mut [u8] =
            unsafe { &mut *(payload as *mut [std::mem::MaybeUninit<u8>] as *mut [u8]) };
        fill(bytes, &mut header)?;
        // SAFETY: as above, every byte is initialised.
        let mut sample = unsafe { sample.assume_init() };
        header.publish_ns = hubtrack_types::time::monotonic_ns();
        *sample.user_header_mut() = header;
        sample.send().map_err(|e| xfer_err("send", spec, e))?;
        // A failed notify only delays a subscriber until its wait times out.
        let _ = self.notifier.notify();
        Ok(header)
    }
}

/// Result of waiting for input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wake {
    /// An event arrived (data may be ready).
    Event,
    /// The timeout passed.
    Timeout,
}

/// Subscribes to camera frames.
pub struct FrameSubscriber {
    subscriber: Subscriber<Ipc, [u8], FrameHeader>,
    /// Woken by each frame's notification; `None` for a polling subscriber.
    listener: Option<Listener<Ipc>>,
    last_seq: Option<u64>,
    /// Frames that were in the buffer but skipped to take the newest one.
    pub skipped: u64,
    /// Frames never seen (seq gaps: overwritten in the buffer or not published to us).
    pub lost: u64,
}

impl FrameSubscriber {
    /// Opens the frames service with a receive buffer of `buffer` frames (1 = newest only),
    /// woken by each frame (for the latency-bound consumer: detect).
    pub fn new(node: &Node<Ipc>, buffer: usize) -> Result<FrameSubscriber, IpcError> {
        let mut s = FrameSubscriber::polling(node, buffer)?;
        s.listener = Some(
            open_event(node, &FRAMES)?
                .listener_builder()
                .create()
                .map_err(|e| svc_err(&FRAMES, e))?,
        );
        Ok(s)
    }

    /// As [`FrameSubscriber::new`] but never woken by the camera: [`FrameSubscriber::wait`]
    /// just sleeps. For throughput-bound consumers (the recorder) whose `buffer` holds the
    /// frames of one sleep. The camera notifies its listeners one after another, and a
    /// consumer woken first can pre-empt the camera before it reaches the next: with the
    /// recorder listening, detect heard of each 1080p frame ~0.9 ms late on a 2-core machine
    /// (the recorder woke first and copied the frame).
    pub fn polling(node: &Node<Ipc>, buffer: usize) -> Result<FrameSubscriber, IpcError> {
        let spec = &FRAMES;
        let service = open_pubsub!(node, spec, [u8], |b| b.user_header::<FrameHeader>());
        let subscriber = service
            .subscriber_builder()
            .buffer_size(buffer.clamp(1, spec.qos.subscriber_max_buffer_size))
            .create()
            .map_err(|e| svc_err(spec, e))?;
        Ok(FrameSubscriber {
            subscriber,
            listener: None,
            last_seq: None,
            skipped: 0,
            lost: 0,
        })
    }

    /// Sleeps until a frame is announced or `timeout` passes (a polling subscriber sleeps
    /// `timeout`).
    pub fn wait(&self, timeout: Duration) -> Wake {
        let Some(listener) = &self.listener else {
            std::thread::sleep(timeout);
            return Wake::Timeout;
        };
        match listener.timed_wait(|_| {}, timeout) {
            Ok(n) if n > 0 => Wake::Event,
            _ => Wake::Timeout,
        }
    }

    fn account(&mut self, seq: u64) {
        if let Some(last) = self.last_seq {
            if seq > last + 1 {
                self.lost += seq - last - 1;
            }
        }
        self.last_seq = Some(seq);
    }

    /// The next frame in order (for the recorder), counting seq gaps as lost.
    pub fn receive(&mut self) -> Result<Option<FrameSample>, IpcError> {
        let s = self
            .subscriber
            .receive()
            .map_err(|e| xfer_err("receive", &FRAMES, e))?;
        if let Some(s) = &s {
            self.account(s.user_header().seq);
        }
        Ok(s)
    }

    /// The newest frame, releasing older ones (for the detector): those count as skipped, seq
    /// gaps between received frames as lost.
    pub fn receive_newest(&mut self) -> Result<Option<FrameSample>, IpcError> {
        let mut newest: Option<FrameSample> = None;
        while let Some(s) = self
            .subscriber
            .receive()
            .map_err(|e| xfer_err("receive", &FRAMES, e))?
        {
            self.account(s.user_header().seq);
            if newest.is_some() {
                self.skipped += 1;
            }
            newest = Some(s);
        }
        Ok(newest)
    }
}

/// Publishes a fixed-size message type on one result service.
pub struct MsgPublisher<T: Debug + ZeroCopySend + Copy + 'static> {
    spec: ServiceSpec,
    publisher: Publisher<Ipc, T, ()>,
    notifier: Notifier<Ipc>,
}

impl<T: Debug + ZeroCopySend + Copy + 'static> MsgPublisher<T> {
    /// Opens `spec` for publishing `T`.
    pub fn new(node: &Node<Ipc>, spec: &ServiceSpec) -> Result<Self, IpcError> {
        let service = open_pubsub!(node, spec, T, |b| b);
        let publisher = service
            .publisher_builder()
            .create()
            .map_err(|e| svc_err(spec, e))?;
        let notifier = open_event(node, spec)?
            .notifier_builder()
            .create()
            .map_err(|e| svc_err(spec, e))?;
        Ok(MsgPublisher {
            spec: *spec,
            publisher,
            notifier,
        })
    }

    /// Sends a copy of `value` (these messages are small) and notifies subscribers; returns how
    /// many subscribers it reached.
    pub fn publish(&self, value: T) -> Result<usize, IpcError> {
        let reached = self
            .publisher
            .send_copy(value)
            .map_err(|e| xfer_err("send", &self.spec, e))?;
        let _ = self.notifier.notify();
        Ok(reached)
    }
}

/// Subscribes to one result service.
pub struct MsgSubscriber<T: Debug + ZeroCopySend + Copy + 'static> {
    spec: ServiceSpec,
    subscriber: Subscriber<Ipc, T, ()>,
    /// Woken by each message; `None` for a polling subscriber.
    listener: Option<Listener<Ipc>>,
}

impl<T: Debug + ZeroCopySend + Copy + 'static> MsgSubscriber<T> {
    /// Opens `spec` for receiving `T` with a buffer of `buffer` messages, woken by each one.
    pub fn new(node: &Node<Ipc>, spec: &ServiceSpec, buffer: usize) -> Result<Self, IpcError> {
        let mut s = Self::polling(node, spec, buffer)?;
        s.listener = Some(
            open_event(node, spec)?
                .listener_builder()
                .create()
                .map_err(|e| svc_err(spec, e))?,
        );
        Ok(s)
    }

    /// As [`MsgSubscriber::new`] but never woken ([`MsgSubscriber::wait`] just sleeps): for
    /// inputs read alongside another one that paces the loop, so that publishers do not
    /// notify a listener nobody waits on.
    pub fn polling(node: &Node<Ipc>, spec: &ServiceSpec, buffer: usize) -> Result<Self, IpcError> {
        let service = open_pubsub!(node, spec, T, |b| b);
        let subscriber = service
            .subscriber_builder()
            .buffer_size(buffer.clamp(1, spec.qos.subscriber_max_buffer_size))
            .create()
            .map_err(|e| svc_err(spec, e))?;
        Ok(MsgSubscriber {
            spec: *spec,
            subscriber,
            listener: None,
        })
    }

    /// Sleeps until a message is announced or `timeout` passes (a polling subscriber sleeps
    /// `timeout`).
    pub fn wait(&self, timeout: Duration) -> Wake {
        let Some(listener) = &self.listener else {
            std::thread::sleep(timeout);
            return Wake::Timeout;
        };
        match listener.timed_wait(|_| {}, timeout) {
            Ok(n) if n > 0 => Wake::Event,
            _ => Wake::Timeout,
        }
    }

    /// The next message, if any.
    pub fn receive(&self) -> Result<Option<T>, IpcError> {
        Ok(self
            .subscriber
            .receive()
            .map_err(|e| xfer_err("receive", &self.spec, e))?
            .map(|s| *s.payload()))
    }

    /// The newest message, dropping older ones.
    pub fn receive_newest(&self) -> Result<Option<T>, IpcError> {
        let mut newest = None;
        while let Some(v) = self.receive()? {
            newest = Some(v);
        }
        Ok(newest)
    }
}
