//! The Foxglove WebSocket server and its channels: the recording's topics, schemas and encodings
//! (from `hubtrack-record`), so one viewer layout works for the live view and for recordings.

use foxglove::websocket::ServerListener;
use foxglove::{
    ChannelBuilder, Context, RawChannel, Schema, WebSocketServer, WebSocketServerHandle,
};
use hubtrack_record::writer::{FRAMES_TOPIC, OVERLAY_TOPIC};
use hubtrack_record::{annotations, compressed_image, ChannelKind};
use hubtrack_runtime::config::LiveConfig;
use std::collections::BTreeMap;
use std::sync::Arc;

/// The message channels served beside the video and its overlay (the recorder's own counters
/// are not: the live view has its own status).
pub const MESSAGE_CHANNELS: [ChannelKind; 6] = [
    ChannelKind::FrameHeader,
    ChannelKind::Detection,
    ChannelKind::Track,
    ChannelKind::Setpoint,
    ChannelKind::Vehicle,
    ChannelKind::Status,
];

/// Why the live view could not start.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// `live.address` is not an address.
    #[error(transparent)]
    Address(#[from] hubtrack_types::params::ParamError),
    /// The SDK refused a channel or could not listen.
    #[error("live view on {address}: {message}")]
    Foxglove {
        /// The configured address.
        address: String,
        /// The SDK's error.
        message: String,
    },
}

/// The served channels.
#[derive(Clone)]
pub struct Channels {
    /// `/frames`: `foxglove.CompressedImage` (protobuf), JPEG.
    pub video: Arc<RawChannel>,
    /// `/frames/overlay`: `foxglove.ImageAnnotations` (JSON).
    pub overlay: Arc<RawChannel>,
    /// The JSON message channels by kind.
    pub messages: BTreeMap<ChannelKind, Arc<RawChannel>>,
}

/// The running server and its channels.
pub struct LiveServer {
    /// Channels to log to.
    pub channels: Channels,
    handle: Option<WebSocketServerHandle>,
    /// Owns the channels: dropping the context closes them.
    _context: Arc<Context>,
}

/// Logs clients coming and going (the SDK reports through `tracing`, which is not printed).
struct ClientLog;

impl ServerListener for ClientLog {
    fn on_client_connect(&self) {
        log::info!("live view: a client connected");
    }
    fn on_client_disconnect(&self) {
        log::info!("live view: a client disconnected");
    }
}

impl LiveServer {
    /// Registers the channels and starts listening on `cfg.address`.
    pub fn start(cfg: &LiveConfig) -> Result<LiveServer, ServeError> {
        let addr = cfg.socket_addr()?;
        let err = |e: foxglove::FoxgloveError| ServeError::Foxglove {
            address: cfg.address.clone(),
            message: e.to_string(),
        };
        let ctx = Context::new();
        let channel = |topic: &str, encoding: &str, schema: Schema| {
            ChannelBuilder::new(topic)
                .context(&ctx)
                .message_encoding(encoding)
                .schema(schema)
                .build_raw()
        };
        let video = channel(
            FRAMES_TOPIC,
            "protobuf",
            Schema::new(
                compressed_image::SCHEMA_NAME,
                "protobuf",
                compressed_image::descriptor_set(),
            ),
        )
        .map_err(err)?;
        let overlay = channel(
            OVERLAY_TOPIC,
            "json",
            Schema::new(
                annotations::SCHEMA_NAME,
                "jsonschema",
                annotations::json_schema(),
            ),
        )
        .map_err(err)?;
        let mut messages = BTreeMap::new();
        for kind in MESSAGE_CHANNELS {
            let schema = Schema::new(kind.schema_name(), "jsonschema", kind.json_schema());
            messages.insert(kind, channel(kind.topic(), "json", schema).map_err(err)?);
        }
        let handle = WebSocketServer::new()
            .name("hubtrack")
            .context(&ctx)
            .bind(addr.ip().to_string(), addr.port())
            .message_backlog_size(cfg.client_queue_messages)
            .listener(Arc::new(ClientLog))
            .start_blocking()
            .map_err(err)?;
        log::info!(
            "live view on ws://{}:{} (Foxglove WebSocket; no authentication: bind to the radio or VPN interface only)",
            addr.ip(),
            handle.port()
        );
        Ok(LiveServer {
            channels: Channels {
                video,
                overlay,
                messages,
            },
            handle: Some(handle),
            _context: ctx,
        })
    }

    /// Clients connected now.
    pub fn clients(&self) -> usize {
        self.handle.as_ref().map_or(0, |h| h.client_count())
    }

    /// Stops listening and drops the clients (without waiting for a stalled one).
    pub fn stop(&mut self) {
        if let Some(h) = self.handle.take() {
            h.stop().detach_all();
        }
    }
}
