// Final gathering on the GPU (SPEC §3.1): the twin of PointGather::round in
// src/estimators/gather.rs. One invocation per point casts the point's rays [first_ray,
// end_ray) in ray order, so a point's sums do not depend on how the host splits the work into
// dispatches: what a dispatch leaves in `states` and `sums` the next one continues from.
// Appended to traverse.wgsl and sampling.wgsl by the host.

struct GatherParams {
    count: u32,
    first_ray: u32,
    end_ray: u32,
    per_round: u32,
    rounds: u32,
    grid_a: u32,
    grid_b: u32,
    weighting: u32,
    seed: vec2<u32>,
    d_min: f32,
    // Rays stop here: --max-distance, or the largest f32.
    t_max: f32,
    has_max: u32,
    has_ao: u32,
    ao_radius: f32,
    padding: u32,
};

// Where a point's rays start: origin.w is the triangle they leave (bit pattern, NONE for
// none), t.w and b.w the low and high halves of the point's random-number key.
struct Start {
    origin: vec4<f32>,
    t: vec4<f32>,
    b: vec4<f32>,
    n: vec4<f32>,
};

// A point's running figures; the AO sums are Kahan sums (value, carry).
struct State {
    escaped: u32,
    dmin: f32,
    ao_open: vec2<f32>,
    ao_total: vec2<f32>,
    // Rays cast for the point, checked on the host.
    rays: u32,
    padding: u32,
};

@group(1) @binding(0) var<uniform> gather_params: GatherParams;
@group(1) @binding(1) var<storage, read> starts: array<Start>;
@group(1) @binding(2) var<storage, read_write> states: array<State>;
// Per point and round: the Kahan sum (value, carry) of 1/d over the round's rays.
@group(1) @binding(3) var<storage, read_write> sums: array<vec2<f32>>;

fn kahan_add(sum: vec2<f32>, value: f32) -> vec2<f32> {
    let y = value - sum.y;
    let total = sum.x + y;
    return vec2(total, (total - sum.x) - y);
}

@compute @workgroup_size(64)
fn gather(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * 64u;
    let p = gather_params;
    if i >= p.count {
        return;
    }
    let start = starts[i];
    let leaving = bitcast<u32>(start.origin.w);
    let key = vec2(bitcast<u32>(start.t.w), bitcast<u32>(start.b.w));
    var state = states[i];
    var stack: Stack;
    var round = p.first_ray / p.per_round;
    var sum = sums[i * p.rounds + round];
    for (var g = p.first_ray; g < p.end_ray; g++) {
        let r = g / p.per_round;
        if r != round {
            sums[i * p.rounds + round] = sum;
            round = r;
            sum = sums[i * p.rounds + round];
        }
        let w = hemisphere(p.weighting, stratified(g - r * p.per_round, p.grid_a, p.grid_b, random_pair(p.seed, key, g)));
        let direction = w.x * start.t.xyz + w.y * start.b.xyz + w.z * start.n.xyz;
        let hit = closest_hit(start.origin.xyz, direction, p.t_max, leaving, &stack);
        state.rays++;
        var inverse = 0.0;
        if hit.hit {
            state.dmin = min(state.dmin, hit.t);
            inverse = 1.0 / max(hit.t, p.d_min);
        } else {
            state.escaped++;
            if p.has_max != 0u {
                inverse = 1.0 / p.t_max;
            }
        }
        sum = kahan_add(sum, inverse);
        if p.has_ao != 0u {
            // Cosine-weighted: cosine-distributed directions weigh 1, uniform ones cos theta.
            let weight = select(w.z, 1.0, p.weighting == 0u);
            state.ao_total = kahan_add(state.ao_total, weight);
            if !hit.hit || hit.t > p.ao_radius {
                state.ao_open = kahan_add(state.ao_open, weight);
            }
        }
    }
    sums[i * p.rounds + round] = sum;
    states[i] = state;
}
