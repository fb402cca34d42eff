//! No write without a key beyond loopback: when the page listens on an address other than
//! loopback (`0.0.0.0` included), every write (any request but GET/HEAD, and the terminal's
//! WebSocket, which carries keys) needs the token, and so does every read of the API unless
//! `--public-read`. The token is printed at start as a URL with `?token=…` (as Jupyter does),
//! or read from `--token-file`; the page keeps it in a cookie (`utile_token`, SameSite=Strict,
//! HttpOnly) set when the URL brings it; scripts send `Authorization: Bearer …`. The page's
//! own files are always served, so it can ask for the token. Without it: 401 and a JSON
//! error. `GET /api/token?token=…` is the page's check of a token typed in: it always needs
//! the token (even with `--public-read`), answers 200 and sets the cookie when it is right.
//! On loopback nothing changes. An axum middleware layer over the router.

use std::net::SocketAddr;
use std::sync::Arc;

use axum::extract::{Request, State};
use axum::http::{header, HeaderValue, Method, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use axum::{Json, Router};
use serde::Serialize;

/// The cookie that keeps the token.
pub const COOKIE: &str = "utile_token";

/// The page's check of a token typed in (answered here, not by the router).
pub const PROBE: &str = "/api/token";

/// The rules of one listener.
#[derive(Clone, Debug)]
pub struct Guard {
    /// The token (`None`: loopback, nothing checked).
    pub token: Option<String>,
    /// `--public-read`: reads need no token.
    pub public_read: bool,
}

/// Why the page's token cannot be had.
#[derive(Debug, thiserror::Error)]
pub enum GuardError {
    /// The system's generator cannot be read.
    #[error("cannot make a token (/dev/urandom: {source}): give --token-file")]
    Random {
        /// Why.
        source: std::io::Error,
    },
    /// `--token-file` cannot be read.
    #[error("--token-file {file}: {source}")]
    File {
        /// The path given.
        file: String,
        /// Why.
        source: std::io::Error,
    },
    /// The token is too short or has characters the URL, a paste or the cookie would change.
    #[error(
        "{0}: the token must be at least 16 characters, each a letter (A-Z, a-z), a digit, \
         '-', '.', '_' or '~': others do not go through the page's URL, a paste and the \
         cookie unchanged"
    )]
    Unfit(String),
}

/// The 401's body: the API's `{"error": …}` and a mark the page asks for the token on.
#[derive(Debug, Serialize)]
struct TokenNeeded {
    error: String,
    token_needed: bool,
}

/// [`PROBE`]'s answer to the right token.
#[derive(Debug, Serialize)]
struct TokenTaken {
    ok: bool,
}

/// `token` (from `whence`) when every character goes through the URL printed at start (as
/// `?token=`, read by the server without decoding), the page's paste (sent
/// `encodeURIComponent`ed) and the cookie unchanged: URL's unreserved characters (RFC 3986),
/// at least 16.
fn fit(token: &str, whence: &str) -> Result<String, GuardError> {
    let fits = token.len() >= 16
        && token
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"-._~".contains(&b));
    if fits {
        Ok(token.to_string())
    } else {
        Err(GuardError::Unfit(whence.to_string()))
    }
}

/// A new random token: 128 bits from the system's generator, in hex.
fn new_token() -> Result<String, GuardError> {
    use std::io::Read;
    let mut b = [0u8; 16];
    std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut b))
        .map_err(|source| GuardError::Random { source })?;
    Ok(b.iter().map(|x| format!("{x:02x}")).collect())
}

impl Guard {
    /// The rules for a page listening on `http`: a token (from `token_file`, else a new one)
    /// unless it is loopback.
    pub fn new(
        http: &SocketAddr,
        token_file: Option<&str>,
        public_read: bool,
    ) -> Result<Guard, GuardError> {
        if http.ip().is_loopback() {
            return Ok(Guard {
                token: None,
                public_read,
            });
        }
        let token = match token_file {
            Some(f) => {
                let t = std::fs::read_to_string(f).map_err(|source| GuardError::File {
                    file: f.to_string(),
                    source,
                })?;
                fit(t.trim(), &format!("--token-file {f}"))?
            }
            None => fit(&new_token()?, "the new token")?,
        };
        Ok(Guard {
            token: Some(token),
            public_read,
        })
    }

    /// The page's URL with the token, for the console (`host` stands for an unspecified
    /// address).
    pub fn url(&self, http: &SocketAddr, host: &str) -> Option<String> {
        let token = self.token.as_ref()?;
        let at = if http.ip().is_unspecified() {
            format!("{host}:{}", http.port())
        } else {
            http.to_string()
        };
        Some(format!("http://{at}/?token={token}"))
    }
}

/// `router` held to `guard`'s rules.
pub fn layer(router: Router, guard: Guard) -> Router {
    router.layer(axum::middleware::from_fn_with_state(Arc::new(guard), check))
}

/// The token a request brings: `?token=`, the cookie, or `Authorization: Bearer`.
fn presented(req: &Request) -> (Option<String>, bool) {
    if let Some(q) = req.uri().query() {
        for pair in q.split('&') {
            if let Some(t) = pair.strip_prefix("token=") {
                return (Some(t.to_string()), true);
            }
        }
    }
    let h = req.headers();
    if let Some(b) = h
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
    {
        return (Some(b.trim().to_string()), false);
    }
    for c in h.get_all(header::COOKIE) {
        for part in c.to_str().unwrap_or("").split(';') {
            if let Some(t) = part
                .trim()
                .strip_prefix(COOKIE)
                .and_then(|r| r.strip_prefix('='))
            {
                return (Some(t.to_string()), false);
            }
        }
    }
    (None, false)
}

/// Equal, in a time that does not tell how much of it matched.
fn same(a: &str, b: &str) -> bool {
    a.len() == b.len() && a.bytes().zip(b.bytes()).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
}

/// The middleware.
async fn check(State(guard): State<Arc<Guard>>, req: Request, next: Next) -> Response {
    let Some(token) = &guard.token else {
        return next.run(req).await;
    };
    let path = req.uri().path();
    let writes = !matches!(*req.method(), Method::GET | Method::HEAD) || path == "/api/terminal";
    let api = path.starts_with("/api/");
    let probe = path == PROBE;
    let needed = writes || probe || (api && !guard.public_read);
    let (given, in_url) = presented(&req);
    let good = given.as_deref().is_some_and(|g| same(g, token));
    if needed && !good {
        let why = if given.is_some() {
            "wrong token"
        } else {
            "this utile live listens beyond this computer: every write needs its token"
        };
        let mut res = (
            StatusCode::UNAUTHORIZED,
            Json(TokenNeeded {
                error: format!(
                    "{why} (the URL printed at its start has it as ?token=…; scripts send \
                     'Authorization: Bearer TOKEN')"
                ),
                token_needed: true,
            }),
        )
            .into_response();
        res.headers_mut()
            .insert(header::WWW_AUTHENTICATE, HeaderValue::from_static("Bearer"));
        return res;
    }
    let mut res = if probe {
        Json(TokenTaken { ok: true }).into_response()
    } else {
        next.run(req).await
    };
    if good && in_url {
        let cookie = format!("{COOKIE}={token}; Path=/; HttpOnly; SameSite=Strict");
        if let Ok(v) = HeaderValue::from_str(&cookie) {
            res.headers_mut().append(header::SET_COOKIE, v);
        }
    }
    res
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_needs_no_token_and_others_get_one() {
        let lo: SocketAddr = "127.0.0.1:8080".parse().unwrap();
        assert!(Guard::new(&lo, None, false).unwrap().token.is_none());
        let any: SocketAddr = "0.0.0.0:8080".parse().unwrap();
        let g = Guard::new(&any, None, false).unwrap();
        let t = g.token.clone().unwrap();
        assert_eq!(t.len(), 32);
        assert_ne!(Guard::new(&any, None, false).unwrap().token.unwrap(), t);
        assert_eq!(
            g.url(&any, "pi").unwrap(),
            format!("http://pi:8080/?token={t}")
        );
        assert!(same("abc", "abc") && !same("abc", "abd") && !same("abc", "ab"));
    }

    #[test]
    fn a_token_has_only_what_the_url_the_paste_and_the_cookie_carry() {
        assert!(fit("a-token_kept.in~a-file-42", "f").is_ok());
        for bad in [
            "short",
            "token+with+plus+signs",
            "token&and=more-things",
            "token%20percent-x",
            "token#with-a-hash-x",
            "token\"quoted\"-xxxxx",
            "token,comma,separated",
            "token\\backslash-xxxx",
            "token;semicolon-xxxx",
            "token with spaces-xx",
            "tökén-with-accents-x",
        ] {
            let e = fit(bad, "--token-file t").unwrap_err().to_string();
            assert!(e.contains("'-', '.', '_' or '~'"), "{bad}: {e}");
        }
    }
}
