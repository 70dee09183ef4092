// Words of the mask pool that changed on the CPU since the slot's copy
// (`mask_pool.rs`'s `SlotEdits`): each item is a word's index in the pool
// and its value. No two items name one word.

@group(0) @binding(ITEMS) var<storage, read> words: array<vec2<u32>>;
@group(0) @binding(ANSWERS) var<storage, read_write> pool: array<u32>;

@compute @workgroup_size(WORKGROUP)
fn patch_pool(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < params.item_count {
        let word = words[id.x];
        pool[word.x] = word.y;
    }
}
