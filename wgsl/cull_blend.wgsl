// Pass 4 of 4 per display, one workgroup, when the scene has blended material bins:
// every visible instance of a blended bin becomes its own draw, back to front. Per
// blended bin (the last bins, from params.first_blend_bin; their ranges from
// params.blend_first on, each one entry per place of its meshes): each visible
// position of the bin writes a record (sort key, id, slot, mesh, level) into the bin's
// range, in the DrawArgs' five words; the records are sorted by (key, id) with a
// bitonic network whose every step puts the smaller at the lower index, so the range
// needs no padding (a partner past the records stands for +infinity and never moves);
// each record then becomes its draw (both eyes: V instances from V * slot), the rest of
// the range is zeroed, and the bin's and the total draw counts are written.
// The key is the sphere center's squared distance from the midpoint of the display's
// eyes (its one view for mono, far and light views), bits inverted: farthest first.
// The CPU twin is sort_blended in src/cull/cpu.rs.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders/bindings.rs.

var<workgroup> blend_total: u32;

@compute @workgroup_size(WORKGROUP_SIZE)
fn blend_main(@builtin(local_invocation_index) local: u32) {
    blend(local);
}

// The rig's blend pass (RIG): a workgroup per member, `blend_main` for each.
@compute @workgroup_size(WORKGROUP_SIZE)
fn blend_rig(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    member = wid.y;
    blend(local);
}

fn blend(local: u32) {
    let n = workgroup_cull_count(local);
    var start = params.blend_first;
    var all = 0u;
    for (var bin = params.first_blend_bin; bin < params.bin_count; bin++) {
        let total = gather(bin, start, n, local);
        sort(start, total, local);
        let capacity = write_draws(bin, start, total, local);
        if (local == 0u) {
            counts[count_index(2u + bin)] = total;
        }
        start += capacity;
        all += total;
    }
    if (local == 0u) {
        counts[count_index(0u)] += all;
    }
}

// Blended instances sort from the midpoint of the display's eyes, or a far layer's
// from its apex (DisplayContext::sort_origin).
fn sort_origin() -> vec3<f32> {
    if (RIG) {
        return rig.views[member].sort_origin;
    }
    if (display.split_keep == 2u) {
        return display.position;
    }
    let both = (display.eye[0].position + display.eye[1].position) * 0.5;
    return select(display.eye[0].position, both, display.views >= 2u);
}

// Writes a record per visible position of `bin` from draws[start] on, in position
// order; returns how many, as a value the whole workgroup agrees on. Each invocation
// walks a span of SPAN positions, so the workgroup scans once per WORKGROUP_SIZE * SPAN
// positions (on lavapipe a scan's barriers cost more than the positions' reads).
fn gather(bin: u32, start: u32, n: u32, local: u32) -> u32 {
    let origin = sort_origin();
    var written = 0u;
    for (var base = 0u; base < n; base += WORKGROUP_SIZE * SPAN) {
        let first = base + local * SPAN;
        let end = min(first + SPAN, n);
        var members = 0u;
        for (var j = first; j < end; j++) {
            members += select(0u, 1u, gathers(j, bin));
        }
        let scan = workgroup_exclusive_scan(local, members);
        var at = start + written + scan.x;
        for (var j = first; j < end; j++) {
            if (gathers(j, bin)) {
                draws[draw_index(at)] = record(j, n, origin);
                at++;
            }
        }
        written += scan.y;
    }
    if (local == 0u) {
        blend_total = written;
    }
    return workgroupUniformLoad(&blend_total);
}

// Whether position j (of those run over) is visible and of `bin`.
fn gathers(j: u32, bin: u32) -> bool {
    return (entry_of(j) & ENTRY_VISIBLE) != 0u && meshes[mesh_of[cull_position(j)]].bin == bin;
}

// Visible position j's record: its sort key (the squared distance of its sphere's
// center from `origin`, bits inverted: farthest first), id, slot, mesh and level, in
// the five words of a DrawArgs.
fn record(j: u32, n: u32, origin: vec3<f32>) -> DrawArgs {
    let k = cull_position(j);
    let level = (entry_of(j) >> ENTRY_LEVEL_SHIFT) & 3u;
    let d = spheres_at(k).xyz - origin;
    let key = ~bitcast<u32>(d.x * d.x + d.y * d.y + d.z * d.z);
    return DrawArgs(key, order[k], flagged_before(level, j, n, 0u), bitcast<i32>(mesh_of[k]), level);
}

// Sorts the `total` records from draws[start] on by (key, id).
fn sort(start: u32, total: u32, local: u32) {
    var size = 1u;
    while (size < total) {
        size <<= 1u;
    }
    for (var k = 2u; k <= size; k <<= 1u) {
        let half = k / 2u;
        for (var t = local; t < size / 2u; t += WORKGROUP_SIZE) {
            let block = t / half;
            order_pair(start, block * k + t % half, block * k + k - 1u - t % half, total);
        }
        storageBarrier();
        for (var h = k / 4u; h > 0u; h >>= 1u) {
            for (var t = local; t < size / 2u; t += WORKGROUP_SIZE) {
                let i = (t / h) * 2u * h + t % h;
                order_pair(start, i, i + h, total);
            }
            storageBarrier();
        }
    }
}

// Puts the smaller of records i < p at i; a p past the records is +infinity.
fn order_pair(start: u32, i: u32, p: u32, total: u32) {
    if (p >= total) {
        return;
    }
    let a = draws[draw_index(start + i)];
    let b = draws[draw_index(start + p)];
    let before = b.index_count < a.index_count
        || (b.index_count == a.index_count && b.instance_count < a.instance_count);
    if (before) {
        draws[draw_index(start + i)] = b;
        draws[draw_index(start + p)] = a;
    }
}

// Turns the sorted records into draws and zeroes the rest of the bin's range; returns
// the range's length (the places of the bin's meshes).
fn write_draws(bin: u32, start: u32, total: u32, local: u32) -> u32 {
    let v = instances_per_object();
    for (var i = local; i < total; i += WORKGROUP_SIZE) {
        let record = draws[draw_index(start + i)];
        let mesh = bitcast<u32>(record.base_vertex);
        let lod = lods[mesh * MAX_LODS + record.first_instance];
        draws[draw_index(start + i)] = DrawArgs(lod.index_count, v, lod.first_index, meshes[mesh].base_vertex, v * record.first_index);
    }
    var capacity = 0u;
    for (var base = 0u; base < params.mesh_count; base += WORKGROUP_SIZE) {
        let m = base + local;
        var places = 0u;
        if (m < params.mesh_count && meshes[m].bin == bin) {
            places = meshes[m].cull_count;
        }
        capacity += workgroup_exclusive_scan(local, places).y;
    }
    for (var i = total + local; i < capacity; i += WORKGROUP_SIZE) {
        draws[draw_index(start + i)] = DrawArgs(0u, 0u, 0u, 0, 0u);
    }
    return capacity;
}
