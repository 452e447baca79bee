//! Who may open the server's WebSocket and debug endpoints: the page's own origin or an allowed one, and the
//! access token when one is required.

use anyhow::Context;

/// Who may open `/ws`: the allowed origins besides the served one, and the token if one is required.
#[derive(Debug, Clone, Default)]
pub struct Access {
    /// Origins allowed besides the page's own (`--allow-origin`), e.g. `http://localhost:3000`.
    pub allow_origins: Vec<String>,
    /// The token `/ws?token=` must carry (`--token`, or generated for a non-loopback address).
    pub token: Option<String>,
}

/// Checks a WebSocket upgrade: a browser's Origin must be this server's own (scheme-less host:port equal to
/// the Host header) or allowed, so that another web page open in the user's browser cannot drive the app;
/// and the token must match when one is required. Err says why (sent back with 403).
pub fn check_access(headers: &axum::http::HeaderMap, token: Option<&str>, access: &Access) -> Result<(), String> {
    if let Some(origin) = headers.get(axum::http::header::ORIGIN) {
        let origin = origin.to_str().map_err(|_| "the Origin header is not text".to_string())?;
        let host = headers.get(axum::http::header::HOST).and_then(|h| h.to_str().ok()).unwrap_or("");
        let origin_host = origin.split_once("://").map_or(origin, |(_, rest)| rest).trim_end_matches('/');
        let same = !host.is_empty() && origin_host.eq_ignore_ascii_case(host);
        if !same && !access.allow_origins.iter().any(|a| a.trim_end_matches('/').eq_ignore_ascii_case(origin)) {
            return Err(format!("origin {origin} is not this server ({host}); start the server with --allow-origin {origin} to allow it"));
        }
    }
    if let Some(want) = &access.token {
        if token != Some(want.as_str()) {
            return Err("a valid access token is required (open the URL the server printed, with ?token=...)".into());
        }
    }
    Ok(())
}

/// A random access token (128 bits from the OS, hex).
pub(super) fn new_token() -> anyhow::Result<String> {
    use std::io::Read;
    let mut b = [0u8; 16];
    std::fs::File::open("/dev/urandom").and_then(|mut f| f.read_exact(&mut b)).context("cannot read /dev/urandom for an access token")?;
    Ok(b.iter().map(|x| format!("{x:02x}")).collect())
}
