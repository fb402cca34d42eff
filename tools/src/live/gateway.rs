//! The Modbus TCP gateway: tokio-modbus's TCP server takes the connections and the MBAP
//! framing; each request goes, as an RTU request to the slave its unit id names, into the one
//! queue in front of the line, and the reply comes back as the uTile gave it (any function
//! code, exceptions included). A uTile that does not answer gives exception 0x0B, as
//! gateways do; `--read-only` refuses every write with exception 01.

use std::future::Future;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Instant;

use tokio::net::TcpListener;
use tokio_modbus::bytes::Bytes;
use tokio_modbus::server::tcp::Server;
use tokio_modbus::{ExceptionCode, Request, Response, SlaveRequest};

use super::queue::{Failure, Job, Origin};
use super::state::{Input, Shared};

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

/// Whether a function code changes something in the slave.
fn writes(function: u8) -> bool {
    matches!(function, 5 | 6 | 15 | 16 | 22 | 23)
}

/// One TCP connection's service.
struct Gateway {
    shared: Arc<Shared>,
}

impl Drop for Gateway {
    fn drop(&mut self) {
        self.shared.tcp.clients.fetch_sub(1, Ordering::Relaxed);
    }
}

type Reply = Result<Response, ExceptionCode>;

impl tokio_modbus::server::Service for Gateway {
    type Request = SlaveRequest<'static>;
    type Response = Response;
    type Exception = ExceptionCode;
    type Future = Pin<Box<dyn Future<Output = Reply> + Send>>;

    fn call(&self, req: Self::Request) -> Self::Future {
        let shared = self.shared.clone();
        Box::pin(async move { forward(&shared, req).await })
    }
}

/// Carries one request through the line's queue.
async fn forward(shared: &Shared, req: SlaveRequest<'static>) -> Reply {
    let t0 = Instant::now();
    let pdu = request_pdu(&req.request);
    let function = pdu[0];
    let refuse = |code| {
        shared.tcp.refused.fetch_add(1, Ordering::Relaxed);
        Err(code)
    };
    if !(1..=247).contains(&req.slave) {
        // Unit id 0 (a broadcast has no reply) and 248..255 reach no uTile.
        return refuse(ExceptionCode::GatewayPathUnavailable);
    }
    if shared.read_only && writes(function) {
        return refuse(ExceptionCode::IllegalFunction);
    }
    let (job, rx) = Job::new(req.slave, pdu, Origin::Gateway);
    if shared.inputs.send(Input::Job(job)).is_err() {
        return refuse(ExceptionCode::GatewayPathUnavailable);
    }
    let done = match rx.await {
        Ok(Ok(done)) => done,
        Ok(Err(Failure::Busy)) => return refuse(ExceptionCode::ServerDeviceBusy),
        Ok(Err(_)) | Err(_) => return refuse(ExceptionCode::GatewayTargetDevice),
    };
    shared.tcp.requests.fetch_add(1, Ordering::Relaxed);
    // What the gateway itself adds: all but the wait for the line and the time on it.
    let overhead = t0.elapsed().saturating_sub(done.waited + done.on_line);
    shared.tcp.overhead(overhead);
    let (&f, data) = done.pdu.split_first().unwrap_or((&0x80, &[4]));
    if f & 0x80 != 0 {
        return Err(ExceptionCode::new(data.first().copied().unwrap_or(4)));
    }
    Ok(Response::Custom(f, Bytes::copy_from_slice(data)))
}

/// Serves Modbus TCP on `listener` until the program ends; a client from outside `allow`
/// (when given) has its connection closed at once and is counted.
pub async fn serve(
    listener: TcpListener,
    shared: Arc<Shared>,
    allow: Vec<super::allow::Cidr>,
) -> std::io::Result<()> {
    let server = Server::new(listener);
    let on_connected = |stream, addr: SocketAddr| {
        let shared = shared.clone();
        let allowed = super::allow::allowed(&allow, addr.ip());
        async move {
            if !allowed {
                shared.tcp.refused_clients.fetch_add(1, Ordering::Relaxed);
                return Ok(None);
            }
            shared.tcp.clients.fetch_add(1, Ordering::Relaxed);
            let _ = tokio::net::TcpStream::set_nodelay(&stream, true);
            Ok(Some((Gateway { shared }, stream)))
        }
    };
    // A client that sends garbage loses its connection; the others go on.
    server.serve(&on_connected, |_err| {}).await
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
