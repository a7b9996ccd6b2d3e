// Closest-hit traversal of hmdist's 8-wide BVH in a compute shader: the GPU twin of
// src/accel/traverse.rs and src/accel/triangle.rs (read those first; this file follows them
// step by step and says where it differs).
//
// Layout (src/gpu/scene.rs writes it):
// - nodes: 14 vec4 per wide node: for row r (min x, min y, min z, max x, max y, max z) the
//   eight children's bounds in vec4 2r (children 0-3) and 2r + 1 (children 4-7); vec4 12 and
//   13 hold the eight child references (bit patterns): a node index, LEAF | block << 3 |
//   (triangles - 1), or EMPTY.
// - triangles: 3 vec4 per block lane (8 lanes per block), the corners; the first corner's w
//   holds the triangle's index in the mesh (bit pattern).
// - locations: per mesh triangle, the block lane that holds it (8 block + lane).
//
// Differences from the CPU, all deliberate:
// - Watertightness cannot rest on the CPU's exact expression order: a shader compiler may
//   fuse a * b - c * d into a fused multiply-add, differently in two triangles that list a
//   shared edge's vertices in opposite orders, and differently at each place the expression
//   is written. So each edge function is one expression, evaluated with its two vertices in a
//   fixed order (lexicographically smaller world position first, chosen by select) and
//   negated where the triangle lists them the other way, and every rounding in it and in the
//   shear is pinned by an explicit fma: the two triangles compute the same operations on the
//   same values and get exactly negated values, whatever the compiler fuses. (Before, the two
//   orders were two expressions, `-(q.x * p.y - q.y * p.x)` one of them: NVIDIA's compiler
//   fused them differently, and 450 of the 6.9e10 rays of `cube`'s 1024² x 65,536 reference
//   slipped through edges on an H200, where lavapipe lets none through.) Exact zeros are not
//   refined in f64 (WGSL has no f64): a ray exactly through an edge then hits both
//   triangles, never neither.
// - Divisions may be up to 2.5 ulp off on Vulkan, so the box test's far distance is widened
//   by 1 + 2 gamma(8) rather than 1 + 2 gamma(3).
// - The test for "coplanar with the triangle the ray leaves" runs in f32 with a looser
//   tolerance than the CPU's f64 one.

// The layout's constants: the host replaces each value with its own (src/gpu/scene.rs,
// traverse_source), so the two cannot drift apart; the values here only let the file parse
// alone. STACK_SIZE is (WIDTH - 1) * depth + 1 for the BVH at hand.
const LEAF: u32 = 0x80000000u;
const EMPTY: u32 = 0xffffffffu;
const WIDTH: u32 = 8u;
const NODE_VEC4S: u32 = 14u;
const STACK_SIZE: u32 = 64u;
const NONE: u32 = 0xffffffffu;

// The traversal stack: child references and their near distances (bit patterns). A caller
// declares one per invocation and passes it to every closest_hit (WGSL zero-fills a function
// variable where it is declared: once per invocation rather than once per ray).
alias Stack = array<vec2<u32>, STACK_SIZE>;
const UNIT_ROUNDOFF: f32 = 5.9604645e-8;

@group(0) @binding(0) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> locations: array<u32>;

fn gamma(n: f32) -> f32 {
    return (n * UNIT_ROUNDOFF) / (1.0 - n * UNIT_ROUNDOFF);
}

// A ray prepared for the box and triangle tests.
struct Ray {
    origin: vec3<f32>,
    inv_direction: vec3<f32>,
    // The watertight test's axis permutation (kz the dominant axis) and shear.
    kx: u32,
    ky: u32,
    kz: u32,
    shear: vec3<f32>,
};

// 1/d, with a zero component replaced by 1e-30 of the same sign (as RayData::new does).
fn safe_inverse(d: f32) -> f32 {
    var safe = d;
    if d == 0.0 {
        safe = bitcast<f32>((bitcast<u32>(d) & 0x80000000u) | bitcast<u32>(1e-30));
    }
    return 1.0 / safe;
}

fn make_ray(origin: vec3<f32>, direction: vec3<f32>) -> Ray {
    var r: Ray;
    r.origin = origin;
    r.inv_direction = vec3(safe_inverse(direction.x), safe_inverse(direction.y), safe_inverse(direction.z));
    let a = abs(direction);
    // The position of the largest component, the first on ties (glam's max_position).
    var kz = 0u;
    if a.y > a.x {
        kz = 1u;
    }
    if a.z > max(a.x, a.y) {
        kz = 2u;
    }
    r.kz = kz;
    r.kx = select(kz + 1u, 0u, kz == 2u);
    r.ky = select(r.kx + 1u, 0u, r.kx == 2u);
    let dz = direction[kz];
    r.shear = vec3(-direction[r.kx] / dz, -direction[r.ky] / dz, 1.0 / dz);
    return r;
}

fn before(p: vec3<f32>, q: vec3<f32>) -> bool {
    return p.x < q.x || (p.x == q.x && (p.y < q.y || (p.y == q.y && p.z < q.z)));
}

// The edge function of (p, q), 2D in the ray's sheared frame, evaluated in a fixed vertex
// order so that the triangle on the edge's other side gets exactly its negation: one
// expression on ordered operands, its rounding fixed by the fma (nothing left to fuse).
fn edge(p: vec2<f32>, q: vec2<f32>, p_world: vec3<f32>, q_world: vec3<f32>) -> f32 {
    let p_first = before(p_world, q_world);
    let u = select(q, p, p_first);
    let v = select(p, q, p_first);
    let e = fma(u.x, v.y, -(u.y * v.x));
    return select(-e, e, p_first);
}

struct TriangleHit {
    hit: bool,
    t: f32,
    within_error: bool,
};

// WatertightRay::intersect: the hit with (p0, p1, p2) at 0 < t <= t_max.
fn intersect(r: Ray, p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, t_max: f32) -> TriangleHit {
    var miss: TriangleHit;
    miss.hit = false;
    let a = p0 - r.origin;
    let b = p1 - r.origin;
    let c = p2 - r.origin;
    let az0 = a[r.kz];
    let bz0 = b[r.kz];
    let cz0 = c[r.kz];
    // A shared vertex must shear to the same point in both of its triangles: fma, not a
    // product and a sum the compiler may or may not fuse at each of the three.
    let a2 = vec2(fma(r.shear.x, az0, a[r.kx]), fma(r.shear.y, az0, a[r.ky]));
    let b2 = vec2(fma(r.shear.x, bz0, b[r.kx]), fma(r.shear.y, bz0, b[r.ky]));
    let c2 = vec2(fma(r.shear.x, cz0, c[r.kx]), fma(r.shear.y, cz0, c[r.ky]));
    let e0 = edge(b2, c2, p1, p2);
    let e1 = edge(c2, a2, p2, p0);
    let e2 = edge(a2, b2, p0, p1);
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return miss;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return miss;
    }
    let az = az0 * r.shear.z;
    let bz = bz0 * r.shear.z;
    let cz = cz0 * r.shear.z;
    let t_scaled = e0 * az + e1 * bz + e2 * cz;
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
        return miss;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
        return miss;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    // The error bound of t (pbrt-v4 §6.8.7).
    let max_zt = max(max(abs(az), abs(bz)), abs(cz));
    let max_xt = max(max(abs(a2.x), abs(b2.x)), abs(c2.x));
    let max_yt = max(max(abs(a2.y), abs(b2.y)), abs(c2.y));
    let delta_z = gamma(3.0) * max_zt;
    let delta_x = gamma(5.0) * (max_xt + max_zt);
    let delta_y = gamma(5.0) * (max_yt + max_zt);
    let delta_e = 2.0 * (gamma(2.0) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = max(max(abs(e0), abs(e1)), abs(e2));
    let delta_t = 3.0 * (gamma(3.0) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * abs(inv_det);
    var hit: TriangleHit;
    hit.hit = true;
    hit.t = t;
    hit.within_error = t <= delta_t;
    return hit;
}

fn corner(lane: u32, k: u32) -> vec4<f32> {
    return triangles[3u * lane + k];
}

// Whether every corner of block lane `other` lies in the plane of block lane `lane`.
fn coplanar(lane: u32, other: u32) -> bool {
    let a = corner(lane, 0u).xyz;
    let normal = cross(corner(lane, 1u).xyz - a, corner(lane, 2u).xyz - a);
    let length = sqrt(dot(normal, normal));
    if length == 0.0 {
        return false;
    }
    var scale = 0.0;
    for (var k = 0u; k < 3u; k++) {
        scale = max(scale, max(max(abs(corner(lane, k).x), abs(corner(lane, k).y)), abs(corner(lane, k).z)));
        scale = max(scale, max(max(abs(corner(other, k).x), abs(corner(other, k).y)), abs(corner(other, k).z)));
    }
    let tolerance = 32.0 * 1.1920929e-7 * scale;
    for (var k = 0u; k < 3u; k++) {
        if abs(dot(normal, corner(other, k).xyz - a) / length) > tolerance {
            return false;
        }
    }
    return true;
}

// Accel::may_take_within_error_hit.
fn may_take_within_error_hit(leaving: u32, lane: u32) -> bool {
    if leaving == NONE {
        return true;
    }
    if bitcast<u32>(corner(lane, 0u).w) == leaving {
        return false;
    }
    return !coplanar(locations[leaving], lane);
}

struct Closest {
    hit: bool,
    t: f32,
    // The block lane of the triangle hit.
    lane: u32,
    // The triangle's index in the mesh: among hits at equal t the lowest wins, as on the CPU,
    // so the answer does not depend on the visit order.
    triangle: u32,
};

// Whether a hit at t on triangle beats c (traverse.rs Closest::beaten_by).
fn beats(t: f32, triangle: u32, c: Closest) -> bool {
    return t < c.t || (t == c.t && triangle < c.triangle);
}

// The first hit along origin + t direction, 0 < t < t_max, visiting children nearest first
// as the CPU does (ties of t go to the lowest triangle index, whatever the order); hits within their own error bound are kept aside and taken only where
// nothing else is hit (and may_take_within_error_hit allows).
fn closest_hit(origin: vec3<f32>, direction: vec3<f32>, t_max: f32, leaving: u32, stack: ptr<function, Stack>) -> Closest {
    let r = make_ray(origin, direction);
    let far_scale = 1.0 + 2.0 * gamma(8.0);
    let negative = r.inv_direction < vec3(0.0);
    var top = 0u;
    var best: Closest;
    best.hit = false;
    best.t = t_max;
    var doubtful: Closest;
    doubtful.hit = false;
    var current = 0u;
    loop {
        if (current & LEAF) == 0u {
            // Test the node's eight children; push the hit ones so that they pop nearest
            // first (ties in slot order), then take the nearest.
            let base = NODE_VEC4S * current;
            var references = array<vec4<u32>, 2>(bitcast<vec4<u32>>(nodes[base + 12u]), bitcast<vec4<u32>>(nodes[base + 13u]));
            let first = top;
            for (var half = 0u; half < 2u; half++) {
                let lo_x = nodes[base + half];
                let lo_y = nodes[base + 2u + half];
                let lo_z = nodes[base + 4u + half];
                let hi_x = nodes[base + 6u + half];
                let hi_y = nodes[base + 8u + half];
                let hi_z = nodes[base + 10u + half];
                let near_x = (select(lo_x, hi_x, negative.x) - r.origin.x) * r.inv_direction.x;
                let near_y = (select(lo_y, hi_y, negative.y) - r.origin.y) * r.inv_direction.y;
                let near_z = (select(lo_z, hi_z, negative.z) - r.origin.z) * r.inv_direction.z;
                let far_x = (select(hi_x, lo_x, negative.x) - r.origin.x) * r.inv_direction.x;
                let far_y = (select(hi_y, lo_y, negative.y) - r.origin.y) * r.inv_direction.y;
                let far_z = (select(hi_z, lo_z, negative.z) - r.origin.z) * r.inv_direction.z;
                let near = max(max(near_x, near_y), max(near_z, vec4(0.0)));
                let far = min(min(far_x, far_y), min(far_z, vec4(best.t))) * far_scale;
                let hit = near <= far;
                for (var k = 0u; k < 4u; k++) {
                    if hit[k] {
                        let entry = vec2(references[half][k], bitcast<u32>(near[k]));
                        var i = top;
                        while i > first && bitcast<f32>((*stack)[i - 1u].y) <= near[k] {
                            (*stack)[i] = (*stack)[i - 1u];
                            i--;
                        }
                        (*stack)[i] = entry;
                        top++;
                    }
                }
            }
            if top > first {
                top--;
                current = (*stack)[top].x;
                continue;
            }
        } else {
            let block = (current & ~LEAF) >> 3u;
            let count = (current & 7u) + 1u;
            for (var k = 0u; k < count; k++) {
                let lane = WIDTH * block + k;
                // Widened, so that a hit whose t equals the best one reaches the exact
                // comparison (traverse.rs Search::leaf).
                let hit = intersect(r, corner(lane, 0u).xyz, corner(lane, 1u).xyz, corner(lane, 2u).xyz, best.t * far_scale);
                let triangle = bitcast<u32>(corner(lane, 0u).w);
                if hit.hit && hit.t < t_max {
                    if !hit.within_error {
                        if (!best.hit && hit.t < best.t) || (best.hit && beats(hit.t, triangle, best)) {
                            best.hit = true;
                            best.t = hit.t;
                            best.lane = lane;
                            best.triangle = triangle;
                        }
                    } else if (!doubtful.hit || beats(hit.t, triangle, doubtful)) && may_take_within_error_hit(leaving, lane) {
                        doubtful.hit = true;
                        doubtful.t = hit.t;
                        doubtful.lane = lane;
                        doubtful.triangle = triangle;
                    }
                }
            }
        }
        // Pop the nearest entry not yet beaten by a closer hit.
        var found = false;
        while top > 0u {
            top--;
            if bitcast<f32>((*stack)[top].y) <= best.t * far_scale {
                current = (*stack)[top].x;
                found = true;
                break;
            }
        }
        if !found {
            break;
        }
    }
    if best.hit {
        return best;
    }
    return doubtful;
}
