//! No other web page can make `utile live` act: one middleware layer in front of every route,
//! on every bind (docs/LIVE.md, "Security"). A browser sends requests for any page the user
//! visits, to any address, loopback included; these rules refuse the ones that page could
//! make, before a handler runs and before anything reaches the line:
//!
//! 1. **Host**, on a loopback bind: a request must name this computer (`localhost`, a loopback
//!    address such as `127.0.0.1` or `[::1]`, any port) or a name given with `--allow-host`.
//!    A hostile site whose name is made to resolve to 127.0.0.1 (DNS rebinding) is then the
//!    page's own origin for the browser, and only the name it sends tells it apart: 421.
//! 2. **Origin**, on every bind: any request but GET and HEAD, and every upgrade (the
//!    terminal's WebSocket carries keys), whose `Origin` is present and is not the page's
//!    own (`http(s)://` and the request's `Host`, or an `--allow-host` name) is refused 403,
//!    `Origin: null` included. Browsers send `Origin` on every such request; scripts (curl,
//!    Python) send none and are let through, as on loopback before.
//! 3. **Keys**: `POST /api/terminal` takes `Content-Type: application/octet-stream` (the
//!    bytes as typed) or `application/json` (`{"keys": "…"}`) only, 415 otherwise: neither is
//!    a type a form or another page's `fetch(…, {mode: "no-cors"})` may send, so the browser
//!    would have to ask first (a CORS preflight), which rule 2 refuses.
//!
//! Jupyter, webpack-dev-server and Vite check the same on localhost. Beyond loopback the
//! token (`guard.rs`) keeps the Host open: a page reached by any name needs the token there.

use std::net::{IpAddr, SocketAddr};
use std::sync::Arc;

use axum::extract::{Request, State};
use axum::http::{header, HeaderMap, Method, StatusCode, Uri};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use super::api::ApiError;

/// The route that types keys by POST.
const KEYS: &str = "/api/terminal";
/// The media types keys may come in (rule 3).
const BYTES: &str = "application/octet-stream";
/// The JSON body of keys, `{"keys": "…"}`.
const JSON: &str = "application/json";

/// The rules of one listener.
#[derive(Clone, Debug)]
pub struct Door {
    /// Bound to loopback: the Host is checked.
    loopback: bool,
    /// `--allow-host`'s names, lower case.
    allowed: Vec<String>,
    /// The page's address, for the words of a refusal.
    page: SocketAddr,
}

/// Why a request is refused at the door.
#[derive(Debug, PartialEq, thiserror::Error)]
pub enum Refused {
    /// A loopback bind asked by another name (rule 1).
    #[error(
        "this utile live answers to this computer's own names only (localhost, 127.0.0.1, \
         [::1]), not to {host:?}: a web page of another site may have made its name point here \
         (DNS rebinding). Open http://{page}/, or give --allow-host NAME for a name of your \
         own (a reverse proxy)"
    )]
    Host {
        /// The Host the request named.
        host: String,
        /// The page's address.
        page: SocketAddr,
    },
    /// A request that acts, sent by another page (rule 2).
    #[error(
        "refused: a page of {origin} may not act here; only utile live's own page writes, \
         sends and types keys (scripts send no Origin header; for a reverse proxy give \
         --allow-host NAME)"
    )]
    Origin {
        /// The Origin the request carried.
        origin: String,
    },
    /// Keys in another type than the two (rule 3).
    #[error(
        "keys go as Content-Type: application/octet-stream (the bytes as typed) or \
         application/json ({{\"keys\": \"EX0\\r\"}}), not {got}: a form or another page cannot \
         send either (curl -H 'Content-Type: application/octet-stream' --data-binary ...)"
    )]
    KeysType {
        /// The type the request named, in words.
        got: String,
    },
}

impl Refused {
    /// The HTTP status.
    pub fn status(&self) -> StatusCode {
        match self {
            Refused::Host { .. } => StatusCode::MISDIRECTED_REQUEST,
            Refused::Origin { .. } => StatusCode::FORBIDDEN,
            Refused::KeysType { .. } => StatusCode::UNSUPPORTED_MEDIA_TYPE,
        }
    }
}

impl IntoResponse for Refused {
    fn into_response(self) -> Response {
        tracing::debug!(status = %self.status(), why = %self, "a request refused at the door");
        ApiError::from(self).into_response()
    }
}

/// `--allow-host NAME`: a host name or an IP address, without a port (clap's value parser).
pub fn host_name(s: &str) -> Result<String, String> {
    let name = s.trim().to_ascii_lowercase();
    let ip = name
        .strip_prefix('[')
        .and_then(|n| n.strip_suffix(']'))
        .unwrap_or(&name);
    let fits = !name.is_empty()
        && (ip.parse::<IpAddr>().is_ok()
            || name
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'.'));
    if fits {
        Ok(name)
    } else {
        Err(format!(
            "{s:?} is no host name: letters, digits, '-' and '.', or an IP address, without a \
             port (e.g. plc.example.org)"
        ))
    }
}

/// The host of an authority (`name[:port]`, `[v6][:port]`), without its port.
fn without_port(authority: &str) -> &str {
    if authority.starts_with('[') {
        return authority.find(']').map_or(authority, |i| &authority[..=i]);
    }
    authority
        .rsplit_once(':')
        .filter(|(_, port)| port.bytes().all(|b| b.is_ascii_digit()))
        .map_or(authority, |(host, _)| host)
}

/// Whether `host` (without port) names this computer.
fn is_loopback(host: &str) -> bool {
    let ip = host
        .strip_prefix('[')
        .and_then(|h| h.strip_suffix(']'))
        .unwrap_or(host);
    host.eq_ignore_ascii_case("localhost") || ip.parse::<IpAddr>().is_ok_and(|a| a.is_loopback())
}

/// The media type of `headers`' Content-Type, lower case without parameters.
fn media_type(headers: &HeaderMap) -> Option<String> {
    let v = headers.get(header::CONTENT_TYPE)?;
    let text = String::from_utf8_lossy(v.as_bytes());
    let kind = text.split(';').next().unwrap_or("").trim();
    Some(kind.to_ascii_lowercase())
}

/// Whether the keys of `POST /api/terminal` come as JSON (`{"keys": "…"}`).
pub fn keys_as_json(headers: &HeaderMap) -> bool {
    media_type(headers).as_deref() == Some(JSON)
}

impl Door {
    /// The rules for a page bound at `page`, with `--allow-host`'s `names`.
    pub fn new(page: SocketAddr, names: &[String]) -> Door {
        Door {
            loopback: page.ip().is_loopback(),
            allowed: names.iter().map(|n| n.to_ascii_lowercase()).collect(),
            page,
        }
    }

    /// Whether `host` (without port) is an `--allow-host` name.
    fn allowed(&self, host: &str) -> bool {
        self.allowed.iter().any(|a| a.eq_ignore_ascii_case(host))
    }

    /// Rule 1: the names a request gives for this server (its Host, and the authority of an
    /// absolute URI).
    fn check_host(&self, uri: &Uri, headers: &HeaderMap) -> Result<(), Refused> {
        if !self.loopback {
            return Ok(());
        }
        let given = headers
            .get_all(header::HOST)
            .iter()
            .map(|h| String::from_utf8_lossy(h.as_bytes()).into_owned())
            .chain(uri.authority().map(|a| a.as_str().to_string()));
        for host in given {
            let name = without_port(host.trim());
            if !is_loopback(name) && !self.allowed(name) {
                return Err(Refused::Host {
                    host,
                    page: self.page,
                });
            }
        }
        Ok(())
    }

    /// Rule 2: a request that acts carries no Origin, or the page's own.
    fn check_origin(&self, method: &Method, headers: &HeaderMap) -> Result<(), Refused> {
        let acts =
            !matches!(*method, Method::GET | Method::HEAD) || headers.contains_key(header::UPGRADE);
        let Some(origin) = headers.get(header::ORIGIN) else {
            return Ok(());
        };
        if !acts {
            return Ok(());
        }
        let origin = String::from_utf8_lossy(origin.as_bytes())
            .trim()
            .to_string();
        let authority = origin
            .strip_prefix("http://")
            .or_else(|| origin.strip_prefix("https://"));
        let own = authority.is_some_and(|a| {
            let host = headers
                .get(header::HOST)
                .map(|h| String::from_utf8_lossy(h.as_bytes()).trim().to_string());
            host.is_some_and(|h| h.eq_ignore_ascii_case(a)) || self.allowed(without_port(a))
        });
        if own {
            Ok(())
        } else {
            Err(Refused::Origin { origin })
        }
    }

    /// Rule 3: keys typed by POST come as bytes or JSON.
    fn check_keys(&self, method: &Method, uri: &Uri, headers: &HeaderMap) -> Result<(), Refused> {
        if *method != Method::POST || uri.path() != KEYS {
            return Ok(());
        }
        match media_type(headers) {
            Some(t) if t == BYTES || t == JSON => Ok(()),
            Some(t) => Err(Refused::KeysType { got: t }),
            None => Err(Refused::KeysType {
                got: "none given".into(),
            }),
        }
    }

    /// All three rules on a request's method, URI and headers.
    pub fn judge(&self, method: &Method, uri: &Uri, headers: &HeaderMap) -> Result<(), Refused> {
        self.check_host(uri, headers)?;
        self.check_origin(method, headers)?;
        self.check_keys(method, uri, headers)
    }
}

/// The middleware: a refused request never reaches a handler.
pub async fn check(State(door): State<Arc<Door>>, req: Request, next: Next) -> Response {
    match door.judge(req.method(), req.uri(), req.headers()) {
        Ok(()) => next.run(req).await,
        Err(refused) => refused.into_response(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::http::HeaderValue;

    fn headers(pairs: &[(header::HeaderName, &str)]) -> HeaderMap {
        let mut h = HeaderMap::new();
        for (k, v) in pairs {
            h.append(k.clone(), HeaderValue::from_str(v).unwrap());
        }
        h
    }

    fn door(bind: &str, names: &[&str]) -> Door {
        let names: Vec<String> = names.iter().map(|n| n.to_string()).collect();
        Door::new(bind.parse().unwrap(), &names)
    }

    fn judge(
        d: &Door,
        method: Method,
        path: &str,
        h: &[(header::HeaderName, &str)],
    ) -> Option<u16> {
        let uri: Uri = path.parse().unwrap();
        d.judge(&method, &uri, &headers(h))
            .err()
            .map(|r| r.status().as_u16())
    }

    #[test]
    fn on_loopback_only_this_computers_names_and_the_allowed_ones() {
        let d = door("127.0.0.1:8080", &["plc.example"]);
        for host in [
            "127.0.0.1:8080",
            "localhost:8080",
            "LOCALHOST",
            "[::1]:8080",
            "127.0.0.1",
            "localhost:9000",
            "plc.example",
            "PLC.example:443",
        ] {
            assert_eq!(
                judge(&d, Method::GET, "/api/state", &[(header::HOST, host)]),
                None,
                "{host}"
            );
        }
        for host in [
            "evil.example:8080",
            "localhost.evil.example",
            "127.0.0.1.nip.io:8080",
            "plc.example.evil",
        ] {
            assert_eq!(
                judge(&d, Method::GET, "/api/state", &[(header::HOST, host)]),
                Some(421),
                "{host}"
            );
            assert_eq!(
                judge(&d, Method::GET, "/", &[(header::HOST, host)]),
                Some(421),
                "{host}"
            );
        }
        // An absolute URI names the server too; no Host at all is no browser.
        assert_eq!(
            judge(&d, Method::GET, "http://evil.example/api/state", &[]),
            Some(421)
        );
        assert_eq!(judge(&d, Method::GET, "/api/state", &[]), None);
        // Beyond loopback any name: the token is the key there.
        let any = door("0.0.0.0:8080", &[]);
        assert_eq!(
            judge(
                &any,
                Method::GET,
                "/api/state",
                &[(header::HOST, "pi.local:8080")]
            ),
            None
        );
    }

    #[test]
    fn a_request_that_acts_with_another_pages_origin_is_refused() {
        for bind in ["127.0.0.1:8080", "0.0.0.0:8080"] {
            let d = door(bind, &["plc.example"]);
            let own = [
                (header::HOST, "127.0.0.1:8080"),
                (header::ORIGIN, "http://127.0.0.1:8080"),
            ];
            let write = "/api/units/1/write";
            assert_eq!(judge(&d, Method::POST, write, &own), None);
            assert_eq!(
                judge(&d, Method::POST, write, &[(header::HOST, "127.0.0.1:8080")]),
                None,
                "no Origin: a script"
            );
            for origin in [
                "http://localhost:9999",
                "http://127.0.0.1:9999",
                "http://localhost:8080",
                "null",
                "file://",
                "http://evil.example",
            ] {
                let h = [(header::HOST, "127.0.0.1:8080"), (header::ORIGIN, origin)];
                for m in [
                    Method::POST,
                    Method::PUT,
                    Method::DELETE,
                    Method::PATCH,
                    Method::OPTIONS,
                ] {
                    assert_eq!(
                        judge(&d, m.clone(), write, &h),
                        Some(403),
                        "{bind} {m} {origin}"
                    );
                }
                // Reads are the browser's to keep from the other page; an upgrade acts.
                assert_eq!(judge(&d, Method::GET, "/api/state", &h), None);
                let ws = [h[0].clone(), h[1].clone(), (header::UPGRADE, "websocket")];
                assert_eq!(judge(&d, Method::GET, KEYS, &ws), Some(403), "{origin}");
            }
            // A reverse proxy's name.
            let proxied = [
                (header::HOST, "127.0.0.1:8080"),
                (header::ORIGIN, "https://plc.example"),
            ];
            assert_eq!(judge(&d, Method::POST, write, &proxied), None);
        }
    }

    #[test]
    fn keys_by_post_come_as_bytes_or_json_only() {
        let d = door("127.0.0.1:8080", &[]);
        let host = (header::HOST, "127.0.0.1:8080");
        for ok in [
            "application/octet-stream",
            "application/json",
            "Application/JSON; charset=utf-8",
        ] {
            assert_eq!(
                judge(
                    &d,
                    Method::POST,
                    KEYS,
                    &[host.clone(), (header::CONTENT_TYPE, ok)]
                ),
                None,
                "{ok}"
            );
        }
        for simple in [
            "text/plain;charset=UTF-8",
            "application/x-www-form-urlencoded",
            "multipart/form-data; boundary=x",
        ] {
            assert_eq!(
                judge(
                    &d,
                    Method::POST,
                    KEYS,
                    &[host.clone(), (header::CONTENT_TYPE, simple)]
                ),
                Some(415),
                "{simple}"
            );
        }
        assert_eq!(
            judge(&d, Method::POST, KEYS, std::slice::from_ref(&host)),
            Some(415),
            "no type"
        );
        // Only the keys' route.
        assert_eq!(judge(&d, Method::POST, "/api/check", &[host]), None);
    }

    #[test]
    fn allowed_names_are_names_without_a_port() {
        assert_eq!(host_name("PLC.Example.org").unwrap(), "plc.example.org");
        assert_eq!(host_name("[::1]").unwrap(), "[::1]");
        assert_eq!(host_name("192.168.1.7").unwrap(), "192.168.1.7");
        for bad in ["", "plc.example:443", "http://plc", "a b", "x/y"] {
            assert!(host_name(bad).is_err(), "{bad:?}");
        }
        assert_eq!(without_port("[::1]:8080"), "[::1]");
        assert_eq!(without_port("localhost"), "localhost");
        assert_eq!(without_port("a.b:80"), "a.b");
    }
}
