//! `POST /debug/carried` given bad requests (issue 30): a real server answers each with 400 and a message naming
//! what is wrong (the field, the number, the count expected), and a good request on the same server is still
//! answered (nothing of the session broke).

mod common;

use common::serve;
use std::io::{Read, Write};
use std::net::TcpStream;

/// POSTs `body` to `/debug/carried` on `http` (host:port); the status code and the body of the answer.
fn post(http: &str, body: &str) -> (u16, String) {
    let mut s = TcpStream::connect(http).unwrap();
    write!(s, "POST /debug/carried HTTP/1.1\r\nHost: {http}\r\nContent-Type: application/json\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}", body.len()).unwrap();
    let mut answer = String::new();
    s.read_to_string(&mut answer).unwrap();
    let status = answer.split_whitespace().nth(1).and_then(|c| c.parse().ok()).unwrap_or(0);
    let body = answer.split_once("\r\n\r\n").map_or("", |(_, b)| b).to_string();
    (status, body)
}

/// A request as JSON: `nodes` numbers (as text), the head's rotation and translation, the vertices.
fn request(nodes: &str, rotation: &str, translation: &str, vertices: &str) -> String {
    format!("{{\"nodes\": [{nodes}], \"head_rotation\": [{rotation}], \"head_translation\": [{translation}], \"vertices\": [{vertices}]}}")
}

#[test]
fn bad_carried_requests_are_refused_naming_what_is_wrong() {
    let s = serve(&["--render-strands", "2000"]);
    const ID: &str = "1, 0, 0, 0, 1, 0, 0, 0, 1";
    // The scene's lattice: the count the server names in its answer to a request with no nodes.
    let (code, why) = post(&s.http, &request("", ID, "0, 0, 0", "0"));
    assert_eq!(code, 400, "{why}");
    let count: usize = why.split("lattice has ").nth(1).and_then(|r| r.split_whitespace().next()).and_then(|n| n.parse().ok()).unwrap_or_else(|| panic!("the node count is named: {why}"));
    assert!(count > 8, "{why}");
    let zeros = |n: usize| vec!["0.0"; n].join(", ");
    let nodes = zeros(3 * count);
    // A good request is answered (its figures are checked against the viewer in the browser test).
    let (code, good) = post(&s.http, &request(&nodes, ID, "0, 0, 0", "0, 1, 31"));
    assert_eq!(code, 200, "{good}");
    assert!(good.contains("\"positions\""), "{good}");
    // The scene's render vertices: the count the server names for a vertex far past the last.
    let (code, why) = post(&s.http, &request(&nodes, ID, "0, 0, 0", "4000000000"));
    assert_eq!(code, 400, "{why}");
    let total: u32 = why.split("the scene has ").nth(1).and_then(|r| r.trim_end_matches(')').parse().ok()).unwrap_or_else(|| panic!("the vertex count is named: {why}"));
    assert_eq!(total % 2000, 0, "2000 render strands: {why}");
    let mut almost = request(&nodes, ID, "0, 0, 0", "0");
    almost.pop();
    let mut out_of_range = zeros(3 * count);
    out_of_range.replace_range(0..3, "1e999");
    let cases: Vec<(&str, String, Vec<String>)> = vec![
        ("malformed JSON", almost, vec!["not a carried request".into(), "EOF".into()]),
        ("not JSON", "hello".into(), vec!["not a carried request".into(), "expected value".into()]),
        ("a field missing", "{\"nodes\": []}".into(), vec!["missing field".into()]),
        ("an unknown field", format!("{{\"colour\": 1, {}", &request(&nodes, ID, "0, 0, 0", "0")[1..]), vec!["unknown field `colour`".into()]),
        ("a string for a number", request(&nodes, "\"I\", 0, 0, 0, 1, 0, 0, 0, 1", "0, 0, 0", "0"), vec!["head_rotation[0]".into()]),
        ("eight numbers for a rotation", request(&nodes, "1, 0, 0, 0, 1, 0, 0, 0", "0, 0, 0", "0"), vec!["head_rotation".into(), "length 8".into(), "length 9".into()]),
        ("two for a translation", request(&nodes, ID, "0, 0", "0"), vec!["head_translation".into(), "length 2".into()]),
        ("a number beyond f64 (JSON has no NaN)", request(&out_of_range, ID, "0, 0, 0", "0"), vec!["nodes".into(), "out of range".into()]),
        ("a negative vertex", request(&nodes, ID, "0, 0, 0", "-1"), vec!["vertices[0]".into()]),
        ("one node too few", request(&zeros(3 * count - 3), ID, "0, 0, 0", "0"), vec![format!("nodes: {} numbers", 3 * count - 3), format!("{count} nodes")]),
        ("a number short of a node", request(&zeros(3 * count + 1), ID, "0, 0, 0", "0"), vec![format!("nodes: {} numbers", 3 * count + 1)]),
        ("a reflection for a rotation", request(&nodes, "-1, 0, 0, 0, 1, 0, 0, 0, 1", "0, 0, 0", "0"), vec!["head_rotation is not a rotation".into(), "reflection".into()]),
        ("a scaled rotation", request(&nodes, "2, 0, 0, 0, 2, 0, 0, 0, 2", "0, 0, 0", "0"), vec!["head_rotation is not a rotation".into(), "3.00e0".into()]),
        ("a vertex past the last", request(&nodes, ID, "0, 0, 0", &format!("0, {total}")), vec![format!("vertices: {total} is not a render vertex"), format!("has {total}")]),
        ("too many vertices", request(&nodes, ID, "0, 0, 0", &vec!["0"; 200_001].join(",")), vec!["200001 asked".into(), "at most 200000".into()]),
    ];
    for (what, body, names) in cases {
        let (code, why) = post(&s.http, &body);
        eprintln!("{what}: {code} {why}");
        assert_eq!(code, 400, "{what}: {why}");
        for n in names {
            assert!(why.contains(&n), "{what}: the answer names {n:?}: {why}");
        }
    }
    // Still answering.
    assert_eq!(post(&s.http, &request(&nodes, ID, "0, 0, 0", "5")).0, 200);
}
