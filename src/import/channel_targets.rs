//! What an animation channel's `target` names, checked on the raw JSON,
//! where channels still have the file's indices (KHR_animation_pointer
//! channels are taken out after this, see `pointer.rs`).
//!
//! The glTF crate does not validate channel targets, yet its accessors
//! unwrap them: a `target.node` past the file's nodes would panic inside
//! import. (A `target.path` glTF does not define is an extension's, which
//! the spec lets a reader ignore: `animation.rs` skips its channel.)
//! Everything else about a target (its type, a missing node) is the
//! schema's to refuse.

use serde_json::Value;

use super::error::Fault;

/// Checks every channel's `target.node`.
pub fn check(document: &Value) -> Result<(), Fault> {
    let nodes = document
        .get("nodes")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    let animations = document.get("animations").and_then(Value::as_array);
    for (a, animation) in animations.into_iter().flatten().enumerate() {
        let channels = animation.get("channels").and_then(Value::as_array);
        for (c, channel) in channels.into_iter().flatten().enumerate() {
            let Some(target) = channel.get("target") else {
                continue;
            };
            let at = |field: &str| format!("animations[{a}].channels[{c}].target.{field}");
            if let Some(node) = target.get("node").and_then(Value::as_u64) {
                if node >= nodes as u64 {
                    let plural = if nodes == 1 { "" } else { "s" };
                    return Err(Fault::Rule {
                        path: at("node"),
                        rule: format!(
                            "is {node}, but the file has {nodes} node{plural}; a channel must \
                             target a node of the file"
                        ),
                    });
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn message(channels: Value) -> Option<String> {
        let document = json!({ "nodes": [{}, {}], "animations": [
            { "channels": [] }, { "channels": channels } ] });
        check(&document).err().map(|fault| fault.to_string())
    }

    #[test]
    fn targets_in_range_pass_whatever_their_path() {
        let channels = json!([
            { "sampler": 0, "target": { "node": 1, "path": "rotation" } },
            { "sampler": 0, "target": { "path": "pointer" } },
            { "sampler": 0, "target": { "node": 0, "path": "visibility" } },
        ]);
        assert_eq!(message(channels), None);
    }

    #[test]
    fn a_node_past_the_file_is_named_by_its_json_path() {
        let channels = json!([
            { "sampler": 0, "target": { "node": 0, "path": "scale" } },
            { "sampler": 0, "target": { "node": 2, "path": "scale" } },
        ]);
        let message = message(channels).expect("node 2 of 2");
        assert!(
            message.starts_with(
                "animations[1].channels[1].target.node: is 2, but the file has 2 nodes"
            ),
            "{message}"
        );
    }
}
