// Hit distances of given rays on the GPU. Appended to traverse.wgsl by the host.

// One ray per invocation, for tests and tools: origin.w is t_max, direction.w the triangle
// the ray leaves (bit pattern, NONE for none); the hit distance comes back, +inf for a miss.
struct TraceRay {
    origin: vec4<f32>,
    direction: vec4<f32>,
};

@group(1) @binding(0) var<storage, read> trace_rays: array<TraceRay>;
@group(1) @binding(1) var<storage, read_write> trace_distances: array<f32>;

@compute @workgroup_size(64)
fn trace(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * 64u;
    if i >= arrayLength(&trace_distances) {
        return;
    }
    let ray = trace_rays[i];
    var stack: Stack;
    let hit = closest_hit(ray.origin.xyz, ray.direction.xyz, ray.origin.w, bitcast<u32>(ray.direction.w), &stack);
    trace_distances[i] = select(bitcast<f32>(0x7f800000u), hit.t, hit.hit);
}
