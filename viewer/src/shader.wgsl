// troupe viewer: lit instanced meshes and a procedural floor grid.

struct Globals {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    // xyz: unit direction towards the key light.
    light_dir: vec4<f32>,
    // Linear colours.
    background: vec4<f32>,
    floor_color: vec4<f32>,
    grid_color: vec4<f32>,
    // xy: target size in pixels.
    viewport: vec4<f32>,
};

@group(0) @binding(0) var<uniform> globals: Globals;

struct MeshOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) color: vec4<f32>,
};

fn quat_rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

@vertex
fn vs_mesh(
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) rotation: vec4<f32>,
    @location(3) translation: vec4<f32>,
    @location(4) scale: vec4<f32>,
    @location(5) color: vec4<f32>,
) -> MeshOut {
    var out: MeshOut;
    let world = quat_rotate(rotation, pos * scale.xyz) + translation.xyz;
    out.clip = globals.view_proj * vec4<f32>(world, 1.0);
    // Inverse-transpose of a non-uniform scale: divide by it.
    out.normal = quat_rotate(rotation, normal / scale.xyz);
    out.color = color;
    return out;
}

@fragment
fn fs_mesh(in: MeshOut) -> @location(0) vec4<f32> {
    let n = normalize(in.normal);
    let key = max(dot(n, globals.light_dir.xyz), 0.0);
    // Hemisphere ambient: brighter from the sky than from the floor.
    let ambient = mix(0.30, 0.55, n.y * 0.5 + 0.5);
    let fill = max(dot(n, normalize(vec3<f32>(-0.6, 0.2, -0.4))), 0.0) * 0.15;
    let shade = ambient + 0.65 * key + fill;
    return vec4<f32>(in.color.rgb * shade, 1.0);
}

struct FloorOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

const FLOOR_HALF: f32 = 80.0;

@vertex
fn vs_floor(@builtin(vertex_index) i: u32) -> FloorOut {
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let c = corners[i] * FLOOR_HALF + floor(globals.eye.xz);
    var out: FloorOut;
    out.world = vec3<f32>(c.x, 0.0, c.y);
    out.clip = globals.view_proj * vec4<f32>(out.world, 1.0);
    return out;
}

// Coverage of the grid lines of `spacing` metres at this fragment; lines whose cells
// shrink under a few pixels fade out instead of shimmering.
fn grid_line(coord: vec2<f32>, spacing: f32) -> f32 {
    let c = coord / spacing;
    let w = max(fwidth(c), vec2<f32>(1e-4));
    let g = abs(fract(c - 0.5) - 0.5) / w;
    let line = 1.0 - min(min(g.x, g.y), 1.0);
    return line * (1.0 - smoothstep(0.08, 0.3, max(w.x, w.y)));
}

@fragment
fn fs_floor(in: FloorOut) -> @location(0) vec4<f32> {
    let major = grid_line(in.world.xz, 1.0);
    let minor = grid_line(in.world.xz, 0.25) * 0.3;
    let line = max(major, minor);
    var color = mix(globals.floor_color.rgb, globals.grid_color.rgb, line);
    let dist = length(in.world - globals.eye.xyz);
    let fade = smoothstep(12.0, 60.0, dist);
    color = mix(color, globals.background.rgb, fade);
    return vec4<f32>(color, 1.0);
}

// Screen-space rectangles (label text and panels), in pixels from the top-left corner.
struct RectOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
};

@vertex
fn vs_rect(
    @builtin(vertex_index) i: u32,
    @location(0) rect: vec4<f32>,
    @location(1) color: vec4<f32>,
) -> RectOut {
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0),
    );
    let p = rect.xy + corners[i] * rect.zw;
    let ndc = vec2<f32>(p.x / globals.viewport.x * 2.0 - 1.0, 1.0 - p.y / globals.viewport.y * 2.0);
    var out: RectOut;
    out.clip = vec4<f32>(ndc, 0.0, 1.0);
    out.color = color;
    return out;
}

@fragment
fn fs_rect(in: RectOut) -> @location(0) vec4<f32> {
    return in.color;
}

// The skin look: linear blend skinning of an actor's skin by its joint matrices.
struct SkinBlock {
    // Linear colours by slot: skin, shirt, trousers, shoes, eye white, pupil, left hand,
    // right hand.
    colors: array<vec4<f32>, 8>,
    joints: array<mat4x4<f32>, 96>,
};

@group(1) @binding(0) var<uniform> skin: SkinBlock;

@vertex
fn vs_skin(
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) joints: vec4<u32>,
    @location(3) weights: vec4<f32>,
    @location(4) part: u32,
) -> MeshOut {
    let m = skin.joints[joints.x] * weights.x + skin.joints[joints.y] * weights.y
        + skin.joints[joints.z] * weights.z + skin.joints[joints.w] * weights.w;
    var out: MeshOut;
    let world = (m * vec4<f32>(pos, 1.0)).xyz;
    out.clip = globals.view_proj * vec4<f32>(world, 1.0);
    // Blended rotations are near-orthogonal: the normal goes through the same matrix.
    out.normal = (m * vec4<f32>(normal, 0.0)).xyz;
    out.color = skin.colors[part];
    return out;
}
