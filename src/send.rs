//! Sending G-code to a print host: Moonraker (Klipper's API server) or OctoPrint, over plain
//! HTTP on the printer's network (native only: the page sends from the browser, www/send.js).
//!
//! - Moonraker: `POST {url}/server/files/upload`, multipart `file` (+ `print=true` to start);
//!   the job state from `GET /server/info` (is Klippy there?) and
//!   `GET /printer/objects/query?print_stats&virtual_sdcard`.
//! - OctoPrint: `POST {url}/api/files/local`, multipart `file`, `select=true`, `print=true|false`;
//!   the job state from `GET /api/job`.
//!
//! The key goes in `X-Api-Key` (OctoPrint needs one; Moonraker only when this computer is not
//! in its `[authorization] trusted_clients`), and nowhere else: no message, error or progress
//! line holds it. The body is built by hand (one boundary that is not in the bytes, the file
//! as `application/octet-stream`) and streamed from memory in 64 KiB pieces, each reported to
//! `progress`. The bytes sent are the bytes given: sending never changes the G-code.
//!
//! Timeouts are bounded: 5 s to connect, 10 s for any small request, and for the upload 60 s
//! plus a second for every 50 KiB (a slow printer board on Wi-Fi still makes it).
//!
//! No TLS: printers on a local network serve http, and the https ones usually show a
//! self-signed certificate that a built-in list of authorities would refuse anyway, so an
//! `https://` address is refused up front with what to do instead.
//!
//! Every failure is a [`SendError`] whose message is one sentence that says what to do.

use std::io::Read;
use std::time::{Duration, Instant};

/// Which kind of print host answers at the address.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum HostKind {
    /// Moonraker, the API server of Klipper (Mainsail, Fluidd).
    Moonraker,
    /// OctoPrint.
    #[value(name = "octoprint")]
    OctoPrint,
}

impl HostKind {
    /// The host's name in messages.
    pub fn label(self) -> &'static str {
        match self {
            HostKind::Moonraker => "Moonraker",
            HostKind::OctoPrint => "OctoPrint",
        }
    }

    fn upload_path(self) -> &'static str {
        match self {
            HostKind::Moonraker => "/server/files/upload",
            HostKind::OctoPrint => "/api/files/local",
        }
    }

    /// A small GET that needs the key: the host's version.
    fn hello_path(self) -> &'static str {
        match self {
            HostKind::Moonraker => "/server/info",
            HostKind::OctoPrint => "/api/version",
        }
    }

    /// Where the user finds the key, for the message of a refused one.
    fn key_help(self) -> &'static str {
        match self {
            HostKind::Moonraker => {
                "give Moonraker's API key (Mainsail or Fluidd: Settings → API key; or GET /access/api_key on the printer) with --key or WEFT_HOST_KEY, or add this computer to Moonraker's [authorization] trusted_clients"
            }
            HostKind::OctoPrint => {
                "make one in OctoPrint under Settings → Application Keys (or your user's settings → API key) and give it with --key or WEFT_HOST_KEY"
            }
        }
    }
}

/// What an upload did.
#[derive(Clone, Debug, PartialEq)]
pub struct Sent {
    /// The file's name on the host (as the host says it stored it).
    pub name: String,
    /// The host, as `HOST:PORT`.
    pub host: String,
    /// Bytes of the file (not counting the form around it).
    pub bytes: u64,
    /// Seconds from the first byte sent to the host's answer.
    pub seconds: f64,
    /// Whether the host started printing it (false when not asked to).
    pub started: bool,
}

/// The host's job, as it reports it.
#[derive(Clone, Debug, PartialEq)]
pub struct JobState {
    /// The host, as `HOST:PORT`.
    pub host: String,
    /// Whether the host talks to the printer (Klippy ready; OctoPrint not offline).
    pub connected: bool,
    /// The host's word for the state: Moonraker's `print_stats.state` (standby, printing,
    /// paused, complete, cancelled, error) or Klippy's state when it is not ready; OctoPrint's
    /// `state` (Operational, Printing, Offline…).
    pub state: String,
    /// Progress of the job, 0 to 100, when there is one.
    pub percent: Option<f64>,
    /// The file of the job, when there is one.
    pub file: Option<String>,
}

impl std::fmt::Display for JobState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if !self.connected {
            return write!(f, "{}: printer not connected ({})", self.host, self.state);
        }
        write!(f, "{}: {}", self.host, self.state)?;
        if let Some(p) = self.percent {
            write!(f, ", {p:.0} %")?;
        }
        if let Some(name) = &self.file {
            write!(f, ", {name}")?;
        }
        Ok(())
    }
}

/// Why sending failed: each message is one sentence with what to do about it. The fields are
/// the parts of that sentence (`host` is HOST:PORT, `words` the host's own, `status` its HTTP
/// status).
#[derive(Debug, thiserror::Error, PartialEq)]
#[allow(missing_docs)] // the fields: named in the sentence above each variant's doc
pub enum SendError {
    /// The address is not http://HOST[:PORT][/path].
    #[error(
        "{url} is not a printer address: give it as http://HOST:PORT (e.g. http://192.168.1.20:7125 for Moonraker, http://192.168.1.20:5000 for OctoPrint)"
    )]
    BadUrl { url: String },
    /// An API key that cannot go in a request header.
    #[error("the API key has a character a key never has (a line break, a space or a non-ASCII letter): paste the key alone, as the host shows it")]
    BadKey,
    /// An https address (or a redirect to one): the CLI has no TLS.
    #[error("{host} is served over https, which the weft CLI does not speak (printers on a local network serve http): give its http:// address, or download the file and upload it in the host's page")]
    Https { host: String },
    /// No connection: nothing listens there, no such host, no route, no answer in time.
    #[error("Cannot reach {host}: check the address and that the printer is on the same network ({why})")]
    Unreachable { host: String, why: String },
    /// 401/403 (OctoPrint's upload: 400 CSRF) with a key: the key is wrong.
    #[error("{host} refused the API key ({status} {words}): {help}")]
    Key { host: String, status: u16, words: String, help: &'static str },
    /// 401/403 (OctoPrint's upload: 400 CSRF) without a key: the host needs one.
    #[error("{host} needs an API key ({status} {words}): {help}")]
    NoKey { host: String, status: u16, words: String, help: &'static str },
    /// 409, or Moonraker's 403 for a file in use: the host did not store the file.
    #[error("{host} did not take {name}: it is busy ({words}); wait for the print to end, or send the file under another name")]
    Busy { host: String, name: String, words: String },
    /// Stored, but not started although asked: busy or not connected (the host's words).
    #[error("Uploaded {name} to {host}, but the printer did not start: it is {words}; start it from the host's page once the printer is ready")]
    NotStarted { host: String, name: String, words: String },
    /// Stored on Moonraker, but not a .gcode it could start.
    #[error("Uploaded {name} to {host}, but the printer did not start: Moonraker starts only plain G-code files (.gcode); send the .gcode to print it")]
    NotGcode { host: String, name: String },
    /// 415: the host does not take this kind of file (OctoPrint and .bgcode).
    #[error("{host} does not take {name} ({status} {words}): send the plain G-code (.gcode) instead")]
    Unsupported { host: String, name: String, status: u16, words: String },
    /// 404/405 where the kind's endpoint should be: another program, or the other kind.
    #[error("{host} does not answer as {kind} ({path}: {status} {words}): check the port and --to (Moonraker listens on 7125, OctoPrint on 80 or 5000)")]
    NotThatHost { host: String, kind: &'static str, path: String, status: u16, words: String },
    /// The connection broke during the upload (`percent` of the file had gone).
    #[error("The upload stopped at {percent} %: nothing was started on the printer ({why}); check the printer's network and send again")]
    Interrupted { percent: u32, why: String },
    /// The host sends its requests to another http address.
    #[error("{host} sends its requests on to {location}: give that address with --url")]
    Redirect { host: String, location: String },
    /// Any other answer that is not a success.
    #[error("{host} answered {status} ({words}): nothing was started; its log says more")]
    Host { host: String, status: u16, words: String },
}

/// The address split for requests: the base URL (no trailing slash) and `HOST:PORT` for messages.
#[derive(Clone, Debug, PartialEq)]
struct Base {
    url: String,
    host: String,
}

/// Checks and normalises a printer address: `http://HOST[:PORT][/prefix]`; a bare
/// `HOST[:PORT]` is taken as http. No user or password in it (keys go in `--key`).
fn base(url: &str) -> Result<Base, SendError> {
    let bad = || SendError::BadUrl { url: url.to_string() };
    let text = url.trim();
    let (scheme, rest) = match text.split_once("://") {
        Some((s, r)) => (s.to_ascii_lowercase(), r),
        None => ("http".to_string(), text),
    };
    let (authority, path) = match rest.find('/') {
        Some(i) => (&rest[..i], rest[i..].trim_end_matches('/')),
        None => (rest, ""),
    };
    if authority.is_empty() || authority.contains('@') || authority.chars().any(|c| c.is_whitespace() || c.is_control()) {
        return Err(bad());
    }
    if path.contains(['?', '#']) || path.chars().any(|c| c.is_whitespace() || c.is_control()) {
        return Err(bad());
    }
    // An IPv6 literal is closed by its bracket; a port, when given, is a number (the literal
    // keeps its colons inside the brackets).
    if authority.starts_with('[') != authority.contains(']') {
        return Err(bad());
    }
    let port = if authority.starts_with('[') { authority.rsplit_once("]:").map(|(_, p)| p) } else { authority.rsplit_once(':').map(|(_, p)| p) };
    if port.is_some_and(|p| p.parse::<u16>().is_err()) {
        return Err(bad());
    }
    match scheme.as_str() {
        "http" => Ok(Base { url: format!("http://{authority}{path}"), host: authority.to_string() }),
        "https" => Err(SendError::Https { host: authority.to_string() }),
        _ => Err(bad()),
    }
}

const CONNECT: Duration = Duration::from_secs(5);
const SMALL_REQUEST: Duration = Duration::from_secs(10);
/// Bytes a second the upload's time limit allows for (a slow board on Wi-Fi).
const SLOWEST_BYTES_PER_SECOND: u64 = 50 * 1024;
/// What a host may say back (an error page, a job state), read at most.
const ANSWER_LIMIT: u64 = 256 * 1024;
const PIECE: usize = 64 * 1024;

fn agent(total: Duration) -> ureq::Agent {
    let config = ureq::Agent::config_builder()
        .http_status_as_error(false)
        .proxy(None)
        .max_redirects(0)
        .max_redirects_will_error(false)
        .timeout_connect(Some(CONNECT))
        .timeout_global(Some(total))
        .user_agent(concat!("weft/", env!("CARGO_PKG_VERSION")))
        .build();
    ureq::Agent::new_with_config(config)
}

/// The upload's time limit for `bytes`.
fn upload_limit(bytes: u64) -> Duration {
    Duration::from_secs(60 + bytes / SLOWEST_BYTES_PER_SECOND)
}

/// A failure before the host answered, in words: unreachable when no connection was made,
/// else interrupted at `percent` (where the body stood).
fn transport_error(e: ureq::Error, host: &str, percent: Option<u32>) -> SendError {
    use std::io::ErrorKind as K;
    let (no_connection, why) = match &e {
        ureq::Error::HostNotFound => (true, "no such host name".to_string()),
        ureq::Error::Timeout(ureq::Timeout::Connect | ureq::Timeout::Resolve) => (true, format!("no answer within {} s", CONNECT.as_secs())),
        ureq::Error::Timeout(t) => (false, format!("the host stopped answering ({t} timeout)")),
        ureq::Error::ConnectionFailed => (true, "the connection failed".to_string()),
        ureq::Error::Io(io) => match io.kind() {
            K::ConnectionRefused => (true, "connection refused: nothing listens at that port".to_string()),
            K::HostUnreachable | K::NetworkUnreachable | K::AddrNotAvailable => (true, "no route to the host".to_string()),
            K::TimedOut => (percent.is_none(), "timed out".to_string()),
            K::ConnectionReset | K::ConnectionAborted | K::BrokenPipe | K::UnexpectedEof => (false, "the host closed the connection".to_string()),
            _ => (false, io.to_string()),
        },
        other => (false, other.to_string()),
    };
    match percent {
        Some(p) if !no_connection => SendError::Interrupted { percent: p, why },
        _ => SendError::Unreachable { host: host.to_string(), why },
    }
}

/// The host's own words in an error answer: Moonraker's `{"error": {"message"}}`, OctoPrint's
/// `{"error": "…"}`, or the first line of a plain text answer; "" when there are none.
fn host_words(body: &str) -> String {
    if let Ok(v) = serde_json::from_str::<serde_json::Value>(body) {
        let e = &v["error"];
        if let Some(s) = e.as_str().or_else(|| e["message"].as_str()).or_else(|| v["message"].as_str()) {
            return s.trim().to_string();
        }
        return String::new();
    }
    // An HTML page or text: its title, else its first line, short.
    let text = match (body.find("<title>"), body.find("</title>")) {
        (Some(a), Some(b)) if b > a => &body[a + 7..b],
        _ => body.lines().find(|l| !l.trim().is_empty()).unwrap_or(""),
    };
    text.trim().chars().take(120).collect()
}

/// `status` with the host's words, for a message: "Unauthorized" when the host said nothing.
fn words_or_reason(status: u16, words: String) -> String {
    let code = status.to_string();
    let words = words.strip_prefix(code.as_str()).map(str::trim_start).unwrap_or(&words);
    // The first sentence is enough ("You don't have the permission … server." is two).
    let words = match words.find(". ") {
        Some(i) => &words[..i],
        None => words.trim_end_matches('.'),
    };
    if !words.is_empty() {
        return words.to_string();
    }
    match status {
        400 => "Bad Request",
        401 => "Unauthorized",
        403 => "Forbidden",
        404 => "Not Found",
        409 => "Conflict",
        415 => "Unsupported Media Type",
        _ => "",
    }
    .to_string()
}

/// Reads an answer's body (at most [`ANSWER_LIMIT`]).
fn body_text(res: &mut ureq::http::Response<ureq::Body>) -> String {
    res.body_mut().with_config().limit(ANSWER_LIMIT).read_to_string().unwrap_or_default()
}

/// Streams `prefix`, `file`, `suffix`, telling `progress` how much of `file` is out.
struct Body<'a, 'p> {
    parts: [&'a [u8]; 3],
    at: (usize, usize),
    progress: &'p mut dyn FnMut(u64, u64),
    file_len: u64,
    sent_of_file: u64,
}

impl Read for Body<'_, '_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        while self.at.0 < 3 {
            let part = self.parts[self.at.0];
            if self.at.1 >= part.len() {
                self.at = (self.at.0 + 1, 0);
                continue;
            }
            let n = (part.len() - self.at.1).min(buf.len()).min(PIECE);
            buf[..n].copy_from_slice(&part[self.at.1..self.at.1 + n]);
            self.at.1 += n;
            if self.at.0 == 1 {
                // Reported as the piece is handed on: the bytes before it are out.
                (self.progress)(self.sent_of_file, self.file_len);
                self.sent_of_file += n as u64;
            } else if self.at.0 == 2 && self.at.1 == n {
                (self.progress)(self.file_len, self.file_len);
            }
            return Ok(n);
        }
        Ok(0)
    }
}

/// A multipart boundary that does not occur in `bytes`.
fn boundary(bytes: &[u8]) -> String {
    let seed = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_nanos()).unwrap_or(0) ^ u128::from(std::process::id());
    (0u32..)
        .map(|i| format!("weft-{:032x}", seed.wrapping_mul(0x9e37_79b9_7f4a_7c15).wrapping_add(u128::from(i))))
        .find(|b| memchr::memmem::find(bytes, b.as_bytes()).is_none())
        .expect("a boundary not in the file")
}

/// A file name as it may stand in a form's `filename="…"`: no folders, quotes or line breaks.
fn form_file_name(name: &str) -> String {
    let base = name.rsplit(['/', '\\']).next().unwrap_or(name);
    let clean: String = base.chars().map(|c| if c == '"' || c.is_control() { '_' } else { c }).collect();
    if clean.trim().is_empty() {
        "weft.gcode".into()
    } else {
        clean
    }
}

/// The multipart form around the file: (content type, prefix, suffix).
fn form(kind: HostKind, file_name: &str, start: bool, bytes: &[u8]) -> (String, Vec<u8>, Vec<u8>) {
    let b = boundary(bytes);
    let mut fields: Vec<(&str, &str)> = Vec::new();
    match kind {
        HostKind::Moonraker => {
            if start {
                fields.push(("print", "true"));
            }
        }
        HostKind::OctoPrint => {
            fields.push(("select", "true"));
            fields.push(("print", if start { "true" } else { "false" }));
        }
    }
    let mut prefix = String::new();
    for (k, v) in fields {
        prefix.push_str(&format!("--{b}\r\nContent-Disposition: form-data; name=\"{k}\"\r\n\r\n{v}\r\n"));
    }
    prefix.push_str(&format!(
        "--{b}\r\nContent-Disposition: form-data; name=\"file\"; filename=\"{}\"\r\nContent-Type: application/octet-stream\r\n\r\n",
        form_file_name(file_name)
    ));
    let suffix = format!("\r\n--{b}--\r\n");
    (format!("multipart/form-data; boundary={b}"), prefix.into_bytes(), suffix.into_bytes())
}

/// The error of a non-success answer to the upload.
fn upload_refused(kind: HostKind, host: &str, name: &str, status: u16, words: String, had_key: bool) -> SendError {
    let host = host.to_string();
    let words_lower = words.to_ascii_lowercase();
    let busy = words_lower.contains("in use") || words_lower.contains("being printed") || words_lower.contains("upload not permitted");
    match status {
        // Moonraker says 403 for a file it is printing; OctoPrint says 400 "CSRF validation
        // failed" to a POST that brought no valid key (it then takes it for a browser session).
        403 | 409 if busy => SendError::Busy { host, name: name.to_string(), words },
        401 | 403 => {
            let words = words_or_reason(status, words);
            if had_key {
                SendError::Key { host, status, words, help: kind.key_help() }
            } else {
                SendError::NoKey { host, status, words, help: kind.key_help() }
            }
        }
        400 if words_lower.contains("csrf") => {
            if had_key {
                SendError::Key { host, status, words, help: kind.key_help() }
            } else {
                SendError::NoKey { host, status, words, help: kind.key_help() }
            }
        }
        409 => SendError::Busy { host, name: name.to_string(), words: words_or_reason(status, words) },
        415 => SendError::Unsupported { host, name: name.to_string(), status, words: words_or_reason(status, words) },
        404 | 405 => SendError::NotThatHost { host, kind: kind.label(), path: kind.upload_path().into(), status, words: words_or_reason(status, words) },
        _ => SendError::Host { host, status, words: words_or_reason(status, words) },
    }
}

/// Uploads `bytes` as `file_name` to the host at `url`, and starts printing it when `start`.
/// `progress(sent, total)` is called as the file goes out (bytes of the file). When the host
/// took the file but did not start it although asked, the error is [`SendError::NotStarted`]
/// (the file is on the host).
pub fn send(
    bytes: &[u8],
    file_name: &str,
    to: HostKind,
    url: &str,
    key: Option<&str>,
    start: bool,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<Sent, SendError> {
    let base = base(url)?;
    let key = key.map(str::trim).filter(|k| !k.is_empty());
    if key.is_some_and(|k| !k.bytes().all(|b| b.is_ascii_graphic())) {
        return Err(SendError::BadKey);
    }
    // A small request first: an address, port or key that is wrong is said before megabytes go.
    get_json(to, &base, to.hello_path(), key)?;
    let (content_type, prefix, suffix) = form(to, file_name, start, bytes);
    let length = (prefix.len() + bytes.len() + suffix.len()) as u64;
    let file_len = bytes.len() as u64;
    let mut body = Body { parts: [&prefix, bytes, &suffix], at: (0, 0), progress, file_len, sent_of_file: 0 };
    let agent = agent(upload_limit(length));
    let mut req = agent.post(format!("{}{}", base.url, to.upload_path())).header("Content-Type", content_type).header("Content-Length", length.to_string());
    if let Some(k) = key {
        req = req.header("X-Api-Key", k);
    }
    let began = Instant::now();
    let answer = req.send(ureq::SendBody::from_reader(&mut body));
    let seconds = began.elapsed().as_secs_f64();
    let percent = (body.sent_of_file * 100).checked_div(file_len).unwrap_or(100) as u32;
    let mut res = answer.map_err(|e| transport_error(e, &base.host, Some(percent.min(99))))?;
    let status = res.status().as_u16();
    let text = body_text(&mut res);
    if !(200..300).contains(&status) {
        return Err(upload_refused(to, &base.host, file_name, status, host_words(&text), key.is_some()));
    }
    let json: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
    // The name the host stored: Moonraker's item.path, OctoPrint's files.local.path.
    let stored = match to {
        HostKind::Moonraker => json["item"]["path"].as_str().or_else(|| json["result"]["item"]["path"].as_str()),
        HostKind::OctoPrint => json["files"]["local"]["path"].as_str(),
    }
    .unwrap_or(file_name)
    .to_string();
    let started = match to {
        HostKind::Moonraker => json["print_started"].as_bool().unwrap_or(false),
        HostKind::OctoPrint => json["effectivePrint"].as_bool().unwrap_or(false),
    };
    if start && !started {
        let queued = json["print_queued"].as_bool().unwrap_or(false);
        let words = if queued {
            "busy (Moonraker queued the file: it starts when the printer is free)".to_string()
        } else if to == HostKind::Moonraker && json.get("print_started").is_none() {
            return Err(SendError::NotGcode { host: base.host, name: stored });
        } else {
            match job_state(to, url, key) {
                Ok(j) if !j.connected => format!("not connected ({})", j.state),
                // Refused while a job was ending: the printer is idle by the time it is asked.
                Ok(j) if is_idle(&j.state) => format!("busy when asked (it is {} now)", j.state),
                Ok(j) => format!("busy ({})", j.state),
                Err(_) => "busy or not connected (the host did not say which)".to_string(),
            }
        };
        return Err(SendError::NotStarted { host: base.host, name: stored, words });
    }
    Ok(Sent { name: stored, host: base.host, bytes: file_len, seconds, started })
}

/// Whether a host's job-state word means the printer is free: OctoPrint's Operational,
/// Moonraker's standby, complete and cancelled.
fn is_idle(state: &str) -> bool {
    matches!(state, "Operational" | "standby" | "complete" | "cancelled")
}

/// A small GET of `path` on the host: its JSON, or the error to report.
fn get_json(kind: HostKind, base: &Base, path: &str, key: Option<&str>) -> Result<(u16, serde_json::Value), SendError> {
    let agent = agent(SMALL_REQUEST);
    let mut req = agent.get(format!("{}{path}", base.url));
    if let Some(k) = key {
        req = req.header("X-Api-Key", k);
    }
    let mut res = req.call().map_err(|e| transport_error(e, &base.host, None))?;
    let status = res.status().as_u16();
    if (300..400).contains(&status) {
        let location = res.headers().get("location").and_then(|l| l.to_str().ok()).unwrap_or("another address").to_string();
        if location.to_ascii_lowercase().starts_with("https:") {
            return Err(SendError::Https { host: base.host.clone() });
        }
        return Err(SendError::Redirect { host: base.host.clone(), location });
    }
    let text = body_text(&mut res);
    match status {
        200..=299 => Ok((status, serde_json::from_str(&text).unwrap_or_default())),
        // Moonraker answers 404 for printer endpoints while Klippy is away.
        404 if path.starts_with("/printer/") => Ok((status, serde_json::Value::Null)),
        401 | 403 => {
            let words = words_or_reason(status, host_words(&text));
            let (host, help) = (base.host.clone(), kind.key_help());
            Err(if key.is_some() { SendError::Key { host, status, words, help } } else { SendError::NoKey { host, status, words, help } })
        }
        404 => Err(SendError::NotThatHost {
            host: base.host.clone(),
            kind: kind.label(),
            path: path.split('?').next().unwrap_or(path).into(),
            status,
            words: words_or_reason(status, host_words(&text)),
        }),
        _ => Err(SendError::Host { host: base.host.clone(), status, words: words_or_reason(status, host_words(&text)) }),
    }
}

/// The host's job now: whether it talks to the printer, its state, progress and file.
pub fn job_state(to: HostKind, url: &str, key: Option<&str>) -> Result<JobState, SendError> {
    let base = base(url)?;
    let key = key.map(str::trim).filter(|k| !k.is_empty());
    match to {
        HostKind::Moonraker => {
            let (_, info) = get_json(to, &base, "/server/info", key)?;
            let klippy = info["result"]["klippy_state"].as_str().unwrap_or("unknown").to_string();
            if klippy != "ready" {
                // Klippy there but the printer not ready: its first line says why.
                let mut state = format!("Klippy {klippy}");
                if info["result"]["klippy_connected"].as_bool() == Some(true) {
                    if let Ok((_, p)) = get_json(to, &base, "/printer/info", key) {
                        if let Some(line) = p["result"]["state_message"].as_str().and_then(|m| m.lines().map(str::trim).find(|l| !l.is_empty())) {
                            state = format!("{state}: {}", line.trim_end_matches('.'));
                        }
                    }
                }
                return Ok(JobState { host: base.host, connected: false, state, percent: None, file: None });
            }
            let (status, q) = get_json(to, &base, "/printer/objects/query?print_stats&virtual_sdcard", key)?;
            if status == 404 {
                return Ok(JobState { host: base.host, connected: false, state: "Klippy not connected".into(), percent: None, file: None });
            }
            let s = &q["result"]["status"];
            let state = s["print_stats"]["state"].as_str().unwrap_or("unknown").to_string();
            let file = s["print_stats"]["filename"].as_str().filter(|f| !f.is_empty()).map(str::to_string);
            let percent = s["virtual_sdcard"]["progress"].as_f64().filter(|_| file.is_some()).map(|p| p * 100.0);
            Ok(JobState { host: base.host, connected: true, state, percent, file })
        }
        HostKind::OctoPrint => {
            let (_, job) = get_json(to, &base, "/api/job", key)?;
            let state = job["state"].as_str().unwrap_or("unknown").to_string();
            let connected = !state.starts_with("Offline") && !state.starts_with("Closed") && state != "unknown";
            let percent = job["progress"]["completion"].as_f64();
            let file = job["job"]["file"]["name"].as_str().map(str::to_string);
            Ok(JobState { host: base.host, connected, state, percent, file })
        }
    }
}

/// Bytes as the progress line says them (binary units, as the rest of weft).
pub fn size(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1024.0 * 1024.0 {
        format!("{:.1} MiB", b / (1024.0 * 1024.0))
    } else if b >= 1024.0 {
        format!("{:.0} KiB", b / 1024.0)
    } else {
        format!("{bytes} bytes")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses() {
        assert_eq!(base("http://127.0.0.1:7125").unwrap(), Base { url: "http://127.0.0.1:7125".into(), host: "127.0.0.1:7125".into() });
        assert_eq!(base(" printer.local:5000/ ").unwrap().url, "http://printer.local:5000");
        assert_eq!(base("http://pi/octoprint/").unwrap().url, "http://pi/octoprint");
        assert_eq!(base("HTTP://[::1]:7125").unwrap().host, "[::1]:7125");
        assert!(matches!(base("https://pi:443"), Err(SendError::Https { .. })));
        for bad in ["", "ftp://pi", "http://", "http://user:pw@pi", "http://pi:port", "http://pi:99999", "http://pi/x?y", "http://[::1", "http://::1]"] {
            assert!(matches!(base(bad), Err(SendError::BadUrl { .. })), "{bad}");
        }
    }

    #[test]
    fn a_key_that_cannot_be_a_header_is_refused_before_any_request() {
        // Port 9 on 127.0.0.1 is not reached: the key is refused first.
        for key in ["ab\ncd", "ab cd", "clé"] {
            let e = send(b"G28\n", "x.gcode", HostKind::OctoPrint, "http://127.0.0.1:9", Some(key), false, &mut |_, _| {}).unwrap_err();
            assert_eq!(e, SendError::BadKey, "{key:?}");
            assert!(!e.to_string().contains(key));
        }
    }

    #[test]
    fn the_form_holds_the_bytes_unchanged_and_a_boundary_not_in_them() {
        let bytes = b"G28\r\n--weft-0\r\nG1 X1\n\x00\xff";
        let (ct, pre, suf) = form(HostKind::OctoPrint, "a\"b\nc.gcode", true, bytes);
        let b = ct.split("boundary=").nth(1).unwrap();
        assert!(memchr::memmem::find(bytes, b.as_bytes()).is_none());
        let pre = String::from_utf8(pre).unwrap();
        assert!(pre.contains("name=\"select\"\r\n\r\ntrue\r\n"));
        assert!(pre.contains("name=\"print\"\r\n\r\ntrue\r\n"));
        assert!(pre.contains("filename=\"a_b_c.gcode\"\r\nContent-Type: application/octet-stream\r\n\r\n"));
        assert_eq!(suf, format!("\r\n--{b}--\r\n").into_bytes());
        let mut seen = Vec::new();
        let mut calls = Vec::new();
        let mut p = |s: u64, t: u64| calls.push((s, t));
        let mut body = Body { parts: [pre.as_bytes(), bytes, &suf], at: (0, 0), progress: &mut p, file_len: bytes.len() as u64, sent_of_file: 0 };
        body.read_to_end(&mut seen).unwrap();
        assert_eq!(seen, [pre.as_bytes(), bytes.as_slice(), &suf].concat());
        assert_eq!(calls.last(), Some(&(bytes.len() as u64, bytes.len() as u64)));
        let (_, pre, _) = form(HostKind::Moonraker, "x.gcode", false, bytes);
        assert!(!String::from_utf8(pre).unwrap().contains("print"));
    }

    #[test]
    fn progress_goes_by_pieces() {
        let bytes = vec![b'G'; 200 * 1024];
        let mut calls = Vec::new();
        let mut p = |s: u64, t: u64| calls.push((s, t));
        let mut body = Body { parts: [b"head", &bytes, b"tail"], at: (0, 0), progress: &mut p, file_len: bytes.len() as u64, sent_of_file: 0 };
        let (mut buf, mut total) = (vec![0; 100_000], 0);
        loop {
            match body.read(&mut buf).unwrap() {
                0 => break,
                n => total += n,
            }
        }
        assert_eq!(total, bytes.len() + 8);
        let sent: Vec<u64> = calls.iter().map(|c| c.0).collect();
        assert_eq!(sent, [0, 65536, 131072, 196608, 204800]);
    }

    #[test]
    fn host_words_read_both_hosts() {
        assert_eq!(host_words(r#"{"error":{"code":401,"message":"Unauthorized","traceback":"x"}}"#), "Unauthorized");
        assert_eq!(host_words("{\n  \"error\": \"CSRF validation failed\"\n}"), "CSRF validation failed");
        assert_eq!(host_words("<html><title>502 Bad Gateway</title></html>"), "502 Bad Gateway");
        assert_eq!(host_words(""), "");
    }

    #[test]
    fn refusals_in_words() {
        let e = upload_refused(HostKind::OctoPrint, "pi:5000", "a.gcode", 400, "CSRF validation failed".into(), false);
        assert!(
            e.to_string().starts_with("pi:5000 needs an API key (400 CSRF validation failed): make one in OctoPrint under Settings → Application Keys"),
            "{e}"
        );
        let e = upload_refused(HostKind::Moonraker, "pi:7125", "a.gcode", 401, "Unauthorized".into(), true);
        assert!(e.to_string().contains("trusted_clients"), "{e}");
        let e = upload_refused(HostKind::OctoPrint, "pi:5000", "a.gcode", 409, "Trying to overwrite file that is currently being printed".into(), true);
        assert!(matches!(e, SendError::Busy { .. }));
        let e = upload_refused(HostKind::Moonraker, "pi:7125", "a.gcode", 403, "File is loaded, upload not permitted".into(), true);
        assert!(matches!(e, SendError::Busy { .. }), "a file being printed is not a key problem");
        let e = upload_refused(HostKind::OctoPrint, "pi:5000", "a.bgcode", 415, "Could not upload file, invalid type".into(), true);
        assert!(e.to_string().contains("send the plain G-code"));
        let e = upload_refused(HostKind::Moonraker, "pi:5000", "a.gcode", 404, String::new(), false);
        assert!(e.to_string().contains("Not Found") && e.to_string().contains("7125"), "{e}");
    }

    #[test]
    fn sizes() {
        assert_eq!(size(12), "12 bytes");
        assert_eq!(size(1536), "2 KiB");
        assert_eq!(size(1_258_291), "1.2 MiB");
    }

    #[test]
    fn a_closed_port_is_unreachable() {
        // A loopback port just freed: nothing listens there.
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let port = l.local_addr().unwrap().port();
        drop(l);
        let e = send(b"G28\n", "a.gcode", HostKind::Moonraker, &format!("http://127.0.0.1:{port}"), None, false, &mut |_, _| {}).unwrap_err();
        assert!(e.to_string().starts_with(&format!("Cannot reach 127.0.0.1:{port}: check the address")), "{e}");
        let e = job_state(HostKind::OctoPrint, &format!("127.0.0.1:{port}"), Some("k")).unwrap_err();
        assert!(matches!(e, SendError::Unreachable { .. }));
    }
}
