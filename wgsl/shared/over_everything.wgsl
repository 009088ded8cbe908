// A display's passes over every cull position (no coarse cull): cull_count,
// cull_position and mesh_range for cull_math.wgsl.

fn cull_count() -> u32 {
    return params.instance_count;
}

fn cull_position(j: u32) -> u32 {
    return j;
}

// Mesh m's (start, count) among what the passes run over.
fn mesh_range(m: u32) -> vec2<u32> {
    return vec2(meshes[m].cull_start, meshes[m].cull_count);
}
