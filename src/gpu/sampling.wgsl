// Random numbers and hemisphere sampling on the GPU: the twin of src/sampling.rs, with the
// same counter-based random numbers (64-bit integer arithmetic emulated on pairs of u32, bit
// for bit the CPU's), the same stratification and the same hemisphere maps (whose sin, cos and
// sqrt may differ from the CPU's in the last bits).

// 64-bit integers as vec2(lo, hi).
fn mul_hi32(x: u32, y: u32) -> u32 {
    let x0 = x & 0xffffu;
    let x1 = x >> 16u;
    let y0 = y & 0xffffu;
    let y1 = y >> 16u;
    let p00 = x0 * y0;
    let p01 = x0 * y1;
    let p10 = x1 * y0;
    let p11 = x1 * y1;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    return p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u);
}

fn mul64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    return vec2(a.x * b.x, mul_hi32(a.x, b.x) + a.x * b.y + a.y * b.x);
}

fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

fn shr64(a: vec2<u32>, n: u32) -> vec2<u32> {
    // 0 < n < 32
    return vec2((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

fn shr64_big(a: vec2<u32>, n: u32) -> vec2<u32> {
    // 32 <= n < 64
    return vec2(a.y >> (n - 32u), 0u);
}

fn mix64(x0: vec2<u32>) -> vec2<u32> {
    var x = x0;
    x = x ^ shr64(x, 27u);
    x = mul64(x, vec2(0x2BA7B653u, 0x3C79AC49u));
    x = x ^ shr64_big(x, 33u);
    x = mul64(x, vec2(0x4AC4AE35u, 0x1C69B3F7u));
    return x ^ shr64(x, 27u);
}

const GOLDEN: vec2<u32> = vec2(0x7F4A7C15u, 0x9E3779B9u);

// sampling::random_pair for a counter below 2^32.
fn random_pair(seed: vec2<u32>, stream: vec2<u32>, counter: u32) -> vec2<f32> {
    let key = mix64(seed ^ GOLDEN);
    let bits = mix64(add64(mix64(key ^ stream), mul64(vec2(counter, 0u), GOLDEN)));
    let scale = 1.0 / 16777216.0;
    return vec2(f32(bits.y >> 8u) * scale, f32((shr64(bits, 8u).x) & 0xffffffu) * scale);
}

// sampling::stratified: point j of an a x b jittered grid.
fn stratified(j: u32, a: u32, b: u32, xi: vec2<f32>) -> vec2<f32> {
    let one_below = 1.0 - 1.1920929e-7;
    return vec2(min((f32(j % a) + xi.x) / f32(a), one_below), min((f32(j / a) + xi.y) / f32(b), one_below));
}

// sampling::hemisphere; weighting 0 is cosine, 1 uniform. The angle is taken in [-pi, pi),
// where Vulkan bounds the error of sin and cos (cos(phi) = -cos(phi - pi), and u.y - 0.5 is
// exact for u.y a multiple of 2^-24).
fn hemisphere(weighting: u32, u: vec2<f32>) -> vec3<f32> {
    var sin_theta: f32;
    var cos_theta: f32;
    if weighting == 0u {
        sin_theta = sqrt(u.x);
        cos_theta = sqrt(1.0 - u.x);
    } else {
        cos_theta = 1.0 - u.x;
        sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    }
    let phi = 6.2831855 * (u.y - 0.5);
    return vec3(-cos(phi) * sin_theta, -sin(phi) * sin_theta, cos_theta);
}

// sampling::Stream::new(seed, stream).bits(counter), for any 64-bit counter.
fn stream_bits(seed: vec2<u32>, stream: vec2<u32>, counter: vec2<u32>) -> vec2<u32> {
    let key = mix64(seed ^ GOLDEN);
    return mix64(add64(mix64(key ^ stream), mul64(counter, GOLDEN)));
}

// sampling::laine_karras: output bit k depends on input bits 0..=k only (Burley 2020).
fn laine_karras(x0: u32, seed: u32) -> u32 {
    var x = x0 + seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// sampling::owen_scramble: Owen's nested uniform scramble of a binary fraction.
fn owen_scramble(x: u32, seed: u32) -> u32 {
    return reverseBits(laine_karras(reverseBits(x), seed));
}

// The first two Sobol dimensions at index i, as binary fractions: the van der Corput sequence
// and, bit by bit, the dimension whose generator matrix is Pascal's triangle mod 2 (the CPU's
// sampling::Progressive::bits computes the same point with its bit reversals folded together).
fn sobol_pair(i: u32) -> vec2<u32> {
    var y = 0u;
    var v = 0x80000000u;
    var bits = i;
    for (var k = 0u; k < 32u; k++) {
        if bits == 0u {
            break;
        }
        if (bits & 1u) != 0u {
            y ^= v;
        }
        bits >>= 1u;
        v ^= v >> 1u;
    }
    return vec2(reverseBits(i), y);
}

// sampling::Progressive::new(Stream::new(seed, stream), replicate): the point's scrambled
// progressive Sobol sequence `replicate`, as its (shuffle, x scramble, y scramble). Made once
// per round, not per ray.
fn progressive(seed: vec2<u32>, stream: vec2<u32>, replicate: u32) -> vec3<u32> {
    // Counters 2^62 + 2 replicate and the one after it.
    let a = stream_bits(seed, stream, vec2(2u * replicate, 0x40000000u));
    let b = stream_bits(seed, stream, vec2(2u * replicate + 1u, 0x40000000u));
    return vec3(a.x, a.y, b.x);
}

// sampling::Progressive::point: point j of the sequence `scramble` (from `progressive`), in
// [0, 1)^2 (24 bits each).
fn progressive_point(scramble: vec3<u32>, j: u32) -> vec2<f32> {
    let xy = sobol_pair(owen_scramble(j, scramble.x));
    let x = owen_scramble(xy.x, scramble.y);
    let y = owen_scramble(xy.y, scramble.z);
    let scale = 1.0 / 16777216.0;
    return vec2(f32(x >> 8u) * scale, f32(y >> 8u) * scale);
}
