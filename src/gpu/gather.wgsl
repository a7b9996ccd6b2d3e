// Final gathering on the GPU (spec §3.1): the twin of PointGather::round in
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
    // R > 0: the cube map by rays (see `texel`), else gather.
    cube_res: u32,
    // 0: each round a jittered grid; 1: each round the first points of its own scrambled
    // Sobol sequence (replicate r for round r).
    sampler: u32,
    padding0: u32,
    padding1: u32,
    padding2: u32,
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

// A hemicube texel (src/estimators/cubemap/hemicube.rs, `lookup` and `texel_direction`, step
// by step): the unit local direction through the centre of the texel that `w` falls in, its
// component along the face's axis, and `w`'s.
struct Texel {
    centre: vec3<f32>,
    centre_along: f32,
    along: f32,
};

fn texel(w: vec3<f32>, r: u32) -> Texel {
    let a = abs(w);
    // The face: axis, and the in-plane directions u (across) and v (up; the normal on the
    // side faces, whose rows count up from the horizon).
    var axis = vec3(0.0, 0.0, 1.0);
    var u = vec3(1.0, 0.0, 0.0);
    var v = vec3(0.0, 1.0, 0.0);
    let top = w.z >= a.x && w.z >= a.y;
    if !top {
        v = vec3(0.0, 0.0, 1.0);
        if a.x >= a.y {
            axis = vec3(sign_of(w.x), 0.0, 0.0);
            u = vec3(0.0, sign_of(w.x), 0.0);
        } else {
            axis = vec3(0.0, sign_of(w.y), 0.0);
            u = vec3(-sign_of(w.y), 0.0, 0.0);
        }
    }
    let along = dot(w, axis);
    let s = dot(w, u) / along;
    let t = dot(w, v) / along;
    let cols = 2u * r;
    let rows = select(r, 2u * r, top);
    // max(0): Rust's `as u32` saturates a slightly negative value to 0.
    let col = min(u32(max((s + 1.0) * 0.5 * f32(cols), 0.0)), cols - 1u);
    let row_f = select(t * f32(rows), (t + 1.0) * 0.5 * f32(rows), top);
    let row = min(u32(max(row_f, 0.0)), rows - 1u);
    let sc = (f32(col) + 0.5) / f32(cols) * 2.0 - 1.0;
    let tc = select((f32(row) + 0.5) / f32(rows), (f32(row) + 0.5) / f32(rows) * 2.0 - 1.0, top);
    let centre = normalize(axis + sc * u + tc * v);
    return Texel(centre, dot(centre, axis), along);
}

// +1 for a positive x, else -1 (the face rule: `w.x > 0` picks +x).
fn sign_of(x: f32) -> f32 {
    return select(-1.0, 1.0, x > 0.0);
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
    // The round's Sobol sequence (sampler 1), made when the round begins.
    var sequence = vec3(0u);
    if p.sampler == 1u {
        sequence = progressive(p.seed, key, round);
    }
    for (var g = p.first_ray; g < p.end_ray; g++) {
        let r = g / p.per_round;
        if r != round {
            sums[i * p.rounds + round] = sum;
            round = r;
            sum = sums[i * p.rounds + round];
            if p.sampler == 1u {
                sequence = progressive(p.seed, key, round);
            }
        }
        var u: vec2<f32>;
        if p.sampler == 1u {
            u = progressive_point(sequence, g - r * p.per_round);
        } else {
            u = stratified(g - r * p.per_round, p.grid_a, p.grid_b, random_pair(p.seed, key, g));
        }
        let w = hemisphere(p.weighting, u);
        state.rays++;
        var inverse = 0.0;
        if p.cube_res > 0u {
            // The cube map by rays: the texel's depth (its centre ray's t times the centre's
            // component along the face axis), as a distance along w, clamped as gather's.
            let x = texel(w, p.cube_res);
            let c = x.centre;
            let through = c.x * start.t.xyz + c.y * start.b.xyz + c.z * start.n.xyz;
            let hit = closest_hit(start.origin.xyz, through, 3.4028235e38, leaving, &stack);
            let d = hit.t * x.centre_along / x.along;
            if hit.hit && (p.has_max == 0u || d <= p.t_max) {
                state.dmin = min(state.dmin, d);
                inverse = 1.0 / max(d, p.d_min);
            } else {
                state.escaped++;
                if p.has_max != 0u {
                    inverse = 1.0 / p.t_max;
                }
            }
            sum = kahan_add(sum, inverse);
            continue;
        }
        let direction = w.x * start.t.xyz + w.y * start.b.xyz + w.z * start.n.xyz;
        let hit = closest_hit(start.origin.xyz, direction, p.t_max, leaving, &stack);
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
