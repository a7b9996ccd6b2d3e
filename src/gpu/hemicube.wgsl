// Hemicube rasterisation and lookup on the GPU (spec §3.2). Mirrors hemicube.rs: the same
// texel layout. The gather directions come from src/gpu/sampling.wgsl, which the host appends.
enable clip_distances;

struct Params {
    atlas_size: vec2<f32>,
    atlas_cols: u32,
    resolution: u32,
    count: u32,
    rays: u32,
    grid_a: u32,
    grid_b: u32,
    weighting: u32,      // 0 cosine, 1 uniform
    has_max: u32,
    seed: vec2<u32>,     // (lo, hi)
    near: f32,
    far: f32,
    d_min: f32,
    d_max: f32,
    first_ray: u32,      // this dispatch's lookups: directions first_ray..end_ray
    end_ray: u32,
    padding: vec2<u32>,
};

// One hemicube: its centre and local frame; n.w holds the pixel index (bit pattern).
struct Cube {
    origin: vec4<f32>,
    t: vec4<f32>,
    b: vec4<f32>,
    n: vec4<f32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> cubes: array<Cube>;

struct FaceFrame {
    axis: vec3<f32>,
    u: vec3<f32>,
    v: vec3<f32>,
};

fn face_frame(face: u32) -> FaceFrame {
    switch face {
        case 0u: { return FaceFrame(vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)); }
        case 1u: { return FaceFrame(vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0), vec3(0.0, 0.0, 1.0)); }
        case 2u: { return FaceFrame(vec3(-1.0, 0.0, 0.0), vec3(0.0, -1.0, 0.0), vec3(0.0, 0.0, 1.0)); }
        case 3u: { return FaceFrame(vec3(0.0, 1.0, 0.0), vec3(-1.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0)); }
        default: { return FaceFrame(vec3(0.0, -1.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0)); }
    }
}

// Top-left atlas texel of `face` of hemicube `cube`, and the face's rows.
fn face_origin(cube: u32, face: u32) -> vec3<u32> {
    let r = params.resolution;
    let x0 = (cube % params.atlas_cols) * 2u * r;
    let block = (cube / params.atlas_cols) * 6u * r;
    if face == 0u {
        return vec3(x0, block, 2u * r);
    }
    return vec3(x0, block + 2u * r + (face - 1u) * r, r);
}

const HORIZON_MARGIN: f32 = 1e-5;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) depth: f32,
    @builtin(clip_distances) clip: array<f32, 4>,
};

@vertex
fn rasterise(@location(0) p: vec3<f32>, @builtin(instance_index) instance: u32) -> VertexOut {
    let cube = instance / 5u;
    let face = instance % 5u;
    let c = cubes[cube];
    let rel = p - c.origin.xyz;
    let local = vec3(dot(rel, c.t.xyz), dot(rel, c.b.xyz), dot(rel, c.n.xyz));
    let f = face_frame(face);
    let w = dot(local, f.axis);
    let s = dot(local, f.u);
    let t = dot(local, f.v);
    var out: VertexOut;
    // Face coordinates, times w: x in [-w, w]; y in [-w, w] (top) or t in [0, w] (sides).
    var y = t;
    if face == 0u {
        out.clip = array<f32, 4>(w - s, w + s, w - t, w + t);
    } else {
        y = 2.0 * t - w;
        // Cut at a hair above the horizon: where the surface point is exact (a floor at
        // y = 0) its plane lies exactly on the horizon, and clipping would leave slivers of
        // it at the near plane in the bottom rows. Texel centres lie at least 1/(2R) above.
        out.clip = array<f32, 4>(w - s, w + s, t - HORIZON_MARGIN * w, w - t);
    }
    let o = face_origin(cube, face);
    let r = f32(params.resolution);
    let h = f32(o.z);
    let size = params.atlas_size;
    let x_clip = w * ((f32(o.x) + r) * 2.0 / size.x - 1.0) + s * (2.0 * r / size.x);
    let y_clip = w * (1.0 - (2.0 * f32(o.y) + h) / size.y) + y * (h / size.y);
    let z_clip = params.far / (params.far - params.near) * (w - params.near);
    out.position = vec4(x_clip, y_clip, z_clip, w);
    out.depth = w;
    return out;
}

@fragment
fn store_depth(@location(0) depth: f32) -> @location(0) vec4<f32> {
    return vec4(depth, 0.0, 0.0, 1.0);
}

// ---- lookups -------------------------------------------------------------------------------

@group(0) @binding(2) var atlas: texture_2d<f32>;
// Per hemicube, carried between dispatches: the Kahan sum of 1/d and its carry, how many
// lookups saw no surface (within --max-distance), and how many were made (checked on the host).
struct Lookup {
    sum: f32,
    carry: f32,
    escaped: u32,
    looked: u32,
}
@group(0) @binding(3) var<storage, read_write> results: array<Lookup>;

@compute @workgroup_size(64)
fn lookup(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.count {
        return;
    }
    let pixel = bitcast<u32>(cubes[i].n.w);
    let a = params.grid_a;
    let b = params.grid_b;
    let r = params.resolution;
    var sum = results[i].sum;
    var carry = results[i].carry; // Kahan summation: up to 65,536 terms in f32
    var escaped = results[i].escaped;
    var looked = results[i].looked;
    for (var j = params.first_ray; j < params.end_ray; j++) {
        looked++;
        let u = stratified(j, a, b, random_pair(params.seed, vec2(pixel, 0u), j));
        let w = hemisphere(params.weighting, u);
        let m = abs(w);
        var face = 0u;
        if !(w.z >= m.x && w.z >= m.y) {
            if m.x >= m.y {
                face = select(2u, 1u, w.x > 0.0);
            } else {
                face = select(4u, 3u, w.y > 0.0);
            }
        }
        let f = face_frame(face);
        let along = dot(w, f.axis);
        let s = dot(w, f.u) / along;
        let t = dot(w, f.v) / along;
        let o = face_origin(i, face);
        let col = min(u32((s + 1.0) * f32(r)), 2u * r - 1u);
        var row: u32;
        if face == 0u {
            row = min(u32((t + 1.0) * f32(r)), 2u * r - 1u);
        } else {
            row = min(u32(t * f32(r)), r - 1u);
        }
        let depth = textureLoad(atlas, vec2(o.x + col, o.y + o.z - 1u - row), 0).x;
        var inverse = 0.0;
        if depth > 0.0 {
            var d = max(depth / along, params.d_min);
            if params.has_max != 0u && d > params.d_max {
                d = params.d_max;
                escaped++;
            }
            inverse = 1.0 / d;
        } else {
            escaped++;
            if params.has_max != 0u {
                inverse = 1.0 / params.d_max;
            }
        }
        let y = inverse - carry;
        let total = sum + y;
        carry = (total - sum) - y;
        sum = total;
    }
    results[i] = Lookup(sum, carry, escaped, looked);
}
