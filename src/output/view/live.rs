//! The live view: the Foxglove SDK's WebSocket server, a sink of the run's context, serving
//! its channels while the run goes (feature `live`).
//!
//! The server speaks the subprotocols the SDK negotiates, `foxglove.sdk.v1` and
//! `foxglove.sdk.v1.1` (the Foxglove app's). It sends each viewer the messages of the channels
//! it subscribed to from then on; with no viewer, nothing is sent and the run does not wait.
//! A viewer that falls behind loses messages (the SDK keeps a backlog of 1024 per viewer),
//! never holds the run back.

use std::net::SocketAddr;
use std::sync::Arc;

use anyhow::Context as _;
use foxglove::{Context, WebSocketServer, WebSocketServerHandle};

/// The address `uncoil run --live` serves on when none is given.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8765";

/// A running server.
pub struct Live {
    handle: WebSocketServerHandle,
    addr: SocketAddr,
}

impl Live {
    /// Starts serving `context`'s channels at `addr` (port 0: a free port).
    pub fn start(context: &Arc<Context>, addr: SocketAddr) -> anyhow::Result<Self> {
        let handle = WebSocketServer::new()
            .name(format!("uncoil {}", env!("CARGO_PKG_VERSION")))
            .context(context)
            .bind(addr.ip().to_string(), addr.port())
            .start_blocking()
            .with_context(|| format!("cannot serve the live view on {addr}"))?;
        let addr = SocketAddr::new(addr.ip(), handle.port());
        Ok(Self { handle, addr })
    }

    /// The address it listens on.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Viewers connected now.
    pub fn viewers(&self) -> usize {
        self.handle.client_count()
    }

    /// Stops serving, after the messages already queued for each viewer are sent.
    pub fn stop(self) {
        self.handle.stop().wait_blocking();
    }
}
