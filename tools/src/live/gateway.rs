//! The Modbus TCP gateway: tokio-modbus's TCP server takes the connections and the MBAP
//! framing; each request goes, as an RTU request to the slave its unit id names, into the one
//! queue in front of the line, and the reply comes back as the uTile gave it (any function
//! code, exceptions included). A uTile that does not answer gives exception 0x0B, as
//! gateways do; a line too busy to take the request within [`WAIT`], exception 06 (nothing
//! was sent); `--read-only` refuses every write with exception 01. The gateway owns its
//! counters and publishes them ([`Counters`], a `watch`) for the state's `line.tcp_…`.

use std::future::Future;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::Arc;
use std::time::{Duration, Instant};

use serde::Serialize;
use tokio::net::TcpListener;
use tokio::sync::watch;
use tokio_modbus::bytes::Bytes;
use tokio_modbus::server::tcp::Server;
use tokio_modbus::{ExceptionCode, Request, Response, SlaveRequest};
use utile_core::modbus::{BROADCAST, MAX_ADDRESS};

use super::allow::{self, Cidr};
use super::hub::Hub;
use super::job::{Failure, Job};
use super::rtu;

/// The longest a request waits for the line to take it (then exception 06, nothing sent).
const WAIT: Duration = Duration::from_secs(5);

/// A mean and a largest figure.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Overhead {
    /// The mean.
    pub mean: f64,
    /// The largest.
    pub max: f64,
}

/// The gateway's figures, as the state shows them beside the line's (`line.tcp_…`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Figures {
    /// Connections open now.
    pub tcp_clients: u64,
    /// Requests carried out.
    pub tcp_requests: u64,
    /// Requests refused (read-only, an address outside 1..247, no answer, busy).
    pub tcp_refused: u64,
    /// Clients refused: not in `--tcp-allow`'s networks.
    pub tcp_refused_clients: u64,
    /// What the gateway added to its requests beyond the wait for the line and the time on
    /// it, ms.
    pub tcp_overhead_ms: Overhead,
    /// The overheads' sum, ms.
    #[serde(skip)]
    overhead_sum_ms: f64,
}

/// The gateway's counters: its tasks count, whoever shows them follows the `watch`.
#[derive(Debug)]
pub struct Counters(watch::Sender<Figures>);

impl Default for Counters {
    fn default() -> Self {
        Counters(watch::channel(Figures::default()).0)
    }
}

impl Counters {
    /// The figures as they change.
    pub fn figures(&self) -> watch::Receiver<Figures> {
        self.0.subscribe()
    }

    /// The figures now.
    pub fn now(&self) -> Figures {
        self.0.borrow().clone()
    }

    fn count(&self, change: impl FnOnce(&mut Figures)) {
        self.0.send_modify(change);
    }

    /// One request carried out, and what the gateway added to it.
    fn carried_out(&self, overhead: Duration) {
        let ms = overhead.as_secs_f64() * 1e3;
        self.count(|f| {
            f.tcp_requests += 1;
            f.overhead_sum_ms += ms;
            f.tcp_overhead_ms = Overhead {
                mean: f.overhead_sum_ms / f.tcp_requests as f64,
                max: f.tcp_overhead_ms.max.max(ms),
            };
        });
    }
}

/// The RTU PDU of a request as the TCP client sent it.
pub fn request_pdu(req: &Request<'_>) -> Vec<u8> {
    let mut pdu = vec![req.function_code().value()];
    let mut word = |w: u16| pdu.extend_from_slice(&w.to_be_bytes());
    match req {
        Request::ReadCoils(a, n)
        | Request::ReadDiscreteInputs(a, n)
        | Request::ReadInputRegisters(a, n)
        | Request::ReadHoldingRegisters(a, n) => {
            word(*a);
            word(*n);
        }
        Request::WriteSingleCoil(a, on) => {
            word(*a);
            word(if *on { 0xFF00 } else { 0 });
        }
        Request::WriteSingleRegister(a, v) => {
            word(*a);
            word(*v);
        }
        Request::WriteMultipleCoils(a, coils) => {
            word(*a);
            word(coils.len() as u16);
            let mut packed = vec![0u8; coils.len().div_ceil(8)];
            for (i, _) in coils.iter().enumerate().filter(|(_, on)| **on) {
                packed[i / 8] |= 1 << (i % 8);
            }
            pdu.push(packed.len() as u8);
            pdu.extend_from_slice(&packed);
        }
        Request::WriteMultipleRegisters(a, words) => {
            word(*a);
            word(words.len() as u16);
            pdu.push((words.len() * 2) as u8);
            for w in words.iter() {
                pdu.extend_from_slice(&w.to_be_bytes());
            }
        }
        Request::ReportServerId => {}
        Request::MaskWriteRegister(a, and, or) => {
            word(*a);
            word(*and);
            word(*or);
        }
        Request::ReadWriteMultipleRegisters(ra, n, wa, words) => {
            word(*ra);
            word(*n);
            word(*wa);
            word(words.len() as u16);
            pdu.push((words.len() * 2) as u8);
            for w in words.iter() {
                pdu.extend_from_slice(&w.to_be_bytes());
            }
        }
        Request::ReadDeviceIdentification(code, object) => {
            pdu.extend_from_slice(&[0x0E, code.value(), *object]);
        }
        Request::Custom(_, data) => pdu.extend_from_slice(data),
    }
    pdu
}

/// One TCP connection's service.
struct Gateway {
    hub: Arc<Hub>,
    counters: Arc<Counters>,
    peer: SocketAddr,
}

impl Drop for Gateway {
    fn drop(&mut self) {
        self.counters.count(|f| f.tcp_clients -= 1);
        tracing::debug!(peer = %self.peer, "a gateway client left");
    }
}

type Reply = Result<Response, ExceptionCode>;

impl tokio_modbus::server::Service for Gateway {
    type Request = SlaveRequest<'static>;
    type Response = Response;
    type Exception = ExceptionCode;
    type Future = Pin<Box<dyn Future<Output = Reply> + Send>>;

    fn call(&self, req: Self::Request) -> Self::Future {
        let (hub, counters) = (self.hub.clone(), self.counters.clone());
        Box::pin(async move { forward(&hub, &counters, req).await })
    }
}

/// Carries one request through the line's queue.
async fn forward(hub: &Hub, counters: &Counters, req: SlaveRequest<'static>) -> Reply {
    let t0 = Instant::now();
    let pdu = request_pdu(&req.request);
    let function = pdu[0];
    let refuse = |code| {
        counters.count(|f| f.tcp_refused += 1);
        Err(code)
    };
    if req.slave == BROADCAST || req.slave > MAX_ADDRESS {
        // Unit id 0 (a broadcast has no reply) and 248..255 reach no uTile.
        return refuse(ExceptionCode::GatewayPathUnavailable);
    }
    if hub.read_only && rtu::is_write(function) {
        return refuse(ExceptionCode::IllegalFunction);
    }
    let done = match hub.ask(Job::gateway(req.slave, pdu), WAIT).await {
        Ok(done) => done,
        Err(Failure::Busy | Failure::NotTaken(_)) => {
            return refuse(ExceptionCode::ServerDeviceBusy)
        }
        Err(Failure::Stopped) => {
            tracing::warn!("a gateway request found the line stopped");
            return refuse(ExceptionCode::GatewayPathUnavailable);
        }
        Err(Failure::NoAnswer | Failure::Editing | Failure::PortClosed) => {
            return refuse(ExceptionCode::GatewayTargetDevice)
        }
    };
    // What the gateway itself adds: all but the wait for the line and the time on it.
    counters.carried_out(t0.elapsed().saturating_sub(done.waited + done.on_line));
    let Some((&f, data)) = done.pdu.split_first() else {
        return Err(ExceptionCode::ServerDeviceFailure);
    };
    if let Some(code) = rtu::exception(&done.pdu) {
        return Err(ExceptionCode::new(code));
    }
    Ok(Response::Custom(f, Bytes::copy_from_slice(data)))
}

/// Serves Modbus TCP on `listener` until the program ends, counting in `counters`; a client
/// from outside `allow` (when given) has its connection closed at once and is counted.
pub async fn serve(
    listener: TcpListener,
    hub: Arc<Hub>,
    allow: Vec<Cidr>,
    counters: Arc<Counters>,
) -> std::io::Result<()> {
    let server = Server::new(listener);
    let on_connected = |stream, peer: SocketAddr| {
        let (hub, counters) = (hub.clone(), counters.clone());
        let allowed = allow::allowed(&allow, peer.ip());
        async move {
            if !allowed {
                counters.count(|f| f.tcp_refused_clients += 1);
                tracing::info!(%peer, "a gateway client outside --tcp-allow refused");
                return Ok(None);
            }
            counters.count(|f| f.tcp_clients += 1);
            tracing::debug!(%peer, "a gateway client connected");
            if let Err(e) = tokio::net::TcpStream::set_nodelay(&stream, true) {
                tracing::debug!(%peer, error = %e, "no TCP_NODELAY: replies may wait");
            }
            Ok(Some((
                Gateway {
                    hub,
                    counters,
                    peer,
                },
                stream,
            )))
        }
    };
    // A client that sends garbage loses its connection; the others go on.
    let on_error = |e| tracing::info!(error = %e, "a gateway connection ended with an error");
    server.serve(&on_connected, on_error).await
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::borrow::Cow;

    #[test]
    fn requests_become_the_pdus_an_rtu_slave_takes() {
        assert_eq!(
            request_pdu(&Request::ReadInputRegisters(64, 40)),
            [4, 0, 64, 0, 40]
        );
        assert_eq!(
            request_pdu(&Request::WriteSingleCoil(8, true)),
            [5, 0, 8, 0xFF, 0]
        );
        assert_eq!(
            request_pdu(&Request::WriteMultipleCoils(
                0,
                Cow::Owned(vec![
                    true, false, true, false, false, false, false, false, true
                ])
            )),
            [15, 0, 0, 0, 9, 2, 0b101, 1]
        );
        assert_eq!(
            request_pdu(&Request::WriteMultipleRegisters(
                24,
                Cow::Owned(vec![500, 700])
            )),
            [16, 0, 24, 0, 2, 4, 1, 0xF4, 2, 0xBC]
        );
        assert_eq!(request_pdu(&Request::ReportServerId), [17]);
        assert_eq!(
            request_pdu(&Request::Custom(8, Cow::Owned(vec![0, 0, 0xAB, 0xCD]))),
            [8, 0, 0, 0xAB, 0xCD]
        );
    }
}
