//! The Modbus TCP gateway: tokio-modbus's TCP server takes the connections and the MBAP
//! framing; each request goes, as an RTU request to the slave its unit id names, into the one
//! queue in front of the line, and the reply comes back as the uTile gave it (any function
//! code, exceptions included). A uTile that does not answer gives exception 0x0B, as
//! gateways do; `--read-only` refuses every write with exception 01.

use std::future::Future;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::Arc;
use std::time::Instant;

use tokio::net::TcpListener;
use tokio_modbus::bytes::Bytes;
use tokio_modbus::server::tcp::Server;
use tokio_modbus::{ExceptionCode, Request, Response, SlaveRequest};
use utile_core::modbus::{BROADCAST, MAX_ADDRESS};

use super::allow::{self, Cidr};
use super::hub::{Hub, Input};
use super::queue::{Failure, Job, Origin};
use super::rtu;

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
    peer: SocketAddr,
}

impl Drop for Gateway {
    fn drop(&mut self) {
        let tcp = &self.hub.tcp;
        tcp.count(&tcp.clients, -1);
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
        let hub = self.hub.clone();
        Box::pin(async move { forward(&hub, req).await })
    }
}

/// Carries one request through the line's queue.
async fn forward(hub: &Hub, req: SlaveRequest<'static>) -> Reply {
    let t0 = Instant::now();
    let pdu = request_pdu(&req.request);
    let function = pdu[0];
    let tcp = &hub.tcp;
    let refuse = |code| {
        tcp.count(&tcp.refused, 1);
        Err(code)
    };
    if req.slave == BROADCAST || req.slave > MAX_ADDRESS {
        // Unit id 0 (a broadcast has no reply) and 248..255 reach no uTile.
        return refuse(ExceptionCode::GatewayPathUnavailable);
    }
    if hub.read_only && rtu::is_write(function) {
        return refuse(ExceptionCode::IllegalFunction);
    }
    let (job, rx) = Job::new(req.slave, pdu, Origin::Gateway);
    if hub.inputs.send(Input::Job(job)).is_err() {
        tracing::warn!("a gateway request found the line stopped");
        return refuse(ExceptionCode::GatewayPathUnavailable);
    }
    let done = match rx.await {
        Ok(Ok(done)) => done,
        Ok(Err(Failure::Busy)) => return refuse(ExceptionCode::ServerDeviceBusy),
        Ok(Err(_)) | Err(_) => return refuse(ExceptionCode::GatewayTargetDevice),
    };
    // What the gateway itself adds: all but the wait for the line and the time on it.
    let overhead = t0.elapsed().saturating_sub(done.waited + done.on_line);
    tcp.overhead(overhead);
    tcp.count(&tcp.requests, 1);
    let Some((&f, data)) = done.pdu.split_first() else {
        return Err(ExceptionCode::ServerDeviceFailure);
    };
    if let Some(code) = rtu::exception(&done.pdu) {
        return Err(ExceptionCode::new(code));
    }
    Ok(Response::Custom(f, Bytes::copy_from_slice(data)))
}

/// Serves Modbus TCP on `listener` until the program ends; a client from outside `allow`
/// (when given) has its connection closed at once and is counted.
pub async fn serve(listener: TcpListener, hub: Arc<Hub>, allow: Vec<Cidr>) -> std::io::Result<()> {
    let server = Server::new(listener);
    let on_connected = |stream, peer: SocketAddr| {
        let hub = hub.clone();
        let allowed = allow::allowed(&allow, peer.ip());
        async move {
            if !allowed {
                hub.tcp.count(&hub.tcp.refused_clients, 1);
                tracing::info!(%peer, "a gateway client outside --tcp-allow refused");
                return Ok(None);
            }
            hub.tcp.count(&hub.tcp.clients, 1);
            tracing::debug!(%peer, "a gateway client connected");
            if let Err(e) = tokio::net::TcpStream::set_nodelay(&stream, true) {
                tracing::debug!(%peer, error = %e, "no TCP_NODELAY: replies may wait");
            }
            Ok(Some((Gateway { hub, peer }, stream)))
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
