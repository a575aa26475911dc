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

// A surface of linear colour `color` facing `normal`, lit by the key light, a fill and
// the sky.
fn lit(color: vec3<f32>, normal: vec3<f32>) -> vec4<f32> {
    let n = normalize(normal);
    let key = max(dot(n, globals.light_dir.xyz), 0.0);
    // Hemisphere ambient: brighter from the sky than from the floor.
    let ambient = mix(0.30, 0.55, n.y * 0.5 + 0.5);
    let fill = max(dot(n, normalize(vec3<f32>(-0.6, 0.2, -0.4))), 0.0) * 0.15;
    let shade = ambient + 0.65 * key + fill;
    return vec4<f32>(color * shade, 1.0);
}

@fragment
fn fs_mesh(in: MeshOut) -> @location(0) vec4<f32> {
    return lit(in.color.rgb, in.normal);
}

struct FloorOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

const FLOOR_HALF: f32 = 80.0;
// Where the pupil begins on the eyeball's front, as a cosine from its axis: set by the
// skin pipeline from `troupe_body::skin::PUPIL_EDGE`, the rule the regions use.
override PUPIL_EDGE: f32;

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

struct SkinOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    // Distances from the volumes of bare skin, shirt, trousers and shoes.
    @location(1) cloth: vec4<f32>,
    // Distance from the nearest eyeball, and where on it (from its centre, in its radii).
    @location(2) eye: vec4<f32>,
    // The vertex's colour slot: a region, or a hand (bare skin tinted by grasp states).
    @location(3) @interpolate(flat) part: u32,
};

// A skin vertex as uploaded (`SkinVertex` in viewer/src/skinned.rs).
struct SkinVertexIn {
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) joints: vec4<u32>,
    @location(3) weights: vec4<f32>,
    // Its colour slot: a region, or a hand (bare skin tinted by grasp states).
    @location(4) part: u32,
    // Multiplies the slot's colour: a user's character's own vertex colour.
    @location(5) tint: vec4<f32>,
    @location(6) cloth: vec4<f32>,
    @location(7) eye: vec4<f32>,
};

// A skin vertex moved by its joints' matrices blended by its weights: its clip position
// and normal.
fn skin_vertex(v: SkinVertexIn) -> MeshOut {
    let m = skin.joints[v.joints.x] * v.weights.x + skin.joints[v.joints.y] * v.weights.y
        + skin.joints[v.joints.z] * v.weights.z + skin.joints[v.joints.w] * v.weights.w;
    let world = (m * vec4<f32>(v.pos, 1.0)).xyz;
    var out: MeshOut;
    out.clip = globals.view_proj * vec4<f32>(world, 1.0);
    // Blended rotations (times the skin's uniform scale) are near-orthogonal up to
    // scale: the normal goes through the same matrix, and `lit` normalises it.
    out.normal = (m * vec4<f32>(v.normal, 0.0)).xyz;
    return out;
}

@vertex
fn vs_skin(v: SkinVertexIn) -> SkinOut {
    let skinned = skin_vertex(v);
    var out: SkinOut;
    out.clip = skinned.clip;
    out.normal = skinned.normal;
    out.cloth = v.cloth;
    out.eye = v.eye;
    out.part = v.part;
    return out;
}

// The far level of detail, a few hundred pixels tall at most, and users' characters:
// coloured by vertex (a character by its own vertex colours, the tint), at the cost of
// the plain meshes; the generated skin's edges between regions are then under a pixel
// or two.
@vertex
fn vs_skin_by_vertex(v: SkinVertexIn) -> MeshOut {
    var out = skin_vertex(v);
    out.color = skin.colors[v.part] * v.tint;
    return out;
}

// A candidate region `k` at distance `d` taken into the nearest two so far (`near`:
// the nearest's distance and the second's; `index`: their regions), without branches.
fn nearest_two(near: vec2<f32>, index: vec2<u32>, d: f32, k: u32) -> vec4<f32> {
    let first = d < near.x;
    let second = d < near.y;
    let d2 = select(select(near.y, d, second), near.x, first);
    let i2 = select(select(index.y, k, second), index.x, first);
    let d1 = select(near.x, d, first);
    let i1 = select(index.x, k, first);
    return vec4<f32>(d1, d2, bitcast<f32>(i1), bitcast<f32>(i2));
}

// The colour of region `k` (bare skin, shirt, trousers, shoes, eye) for a fragment of
// colour slot `part`: bare skin on a hand takes its hand's slot.
fn region_color(k: u32, part: u32, eye: vec4<f32>) -> vec4<f32> {
    let slot = select(k, select(0u, part, part >= 6u), k == 0u);
    return select(skin.colors[min(slot, 7u)], eye, k == 4u);
}

// The skin's colour per pixel: the region whose volumes are nearest, from the
// distances interpolated between the vertices, so that the edges between regions run
// through the triangles where the volumes put them instead of zigzagging along the
// triangles' edges. Across an edge the two regions' colours blend over about a pixel
// (the screen-space change of the distances' difference), as multisampling does for the
// outline.
@fragment
fn fs_skin(in: SkinOut) -> @location(0) vec4<f32> {
    var n = vec4<f32>(in.cloth.x, 1e9, bitcast<f32>(0u), bitcast<f32>(0u));
    n = nearest_two(n.xy, bitcast<vec2<u32>>(n.zw), in.cloth.y, 1u);
    n = nearest_two(n.xy, bitcast<vec2<u32>>(n.zw), in.cloth.z, 2u);
    n = nearest_two(n.xy, bitcast<vec2<u32>>(n.zw), in.cloth.w, 3u);
    n = nearest_two(n.xy, bitcast<vec2<u32>>(n.zw), in.eye.x, 4u);
    let index = bitcast<vec2<u32>>(n.zw);
    let gap = n.y - n.x;
    // The pupil: the eyeball's front, cut by direction from its centre per pixel, so it
    // is round however coarse the eyeball's triangles.
    let pupil = normalize(in.eye.yzw).z - PUPIL_EDGE;
    let eye = mix(
        skin.colors[4],
        skin.colors[5],
        clamp(pupil / max(fwidth(pupil), 1e-6) + 0.5, 0.0, 1.0),
    );
    let near = clamp(gap / max(fwidth(gap), 1e-6) + 0.5, 0.5, 1.0);
    let color = mix(
        region_color(index.y, in.part, eye),
        region_color(index.x, in.part, eye),
        near,
    );
    return lit(color.rgb, in.normal);
}

// Debug lines: a segment per instance, widened into a screen-space quad of `a.w` pixels
// (of a 720-pixel-high picture) around the projected segment, with square caps.
struct LineOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
};

@vertex
fn vs_line(
    @builtin(vertex_index) i: u32,
    @location(0) a: vec4<f32>,
    @location(1) b: vec4<f32>,
    @location(2) color: vec4<f32>,
) -> LineOut {
    var out: LineOut;
    out.color = color;
    var ca = globals.view_proj * vec4<f32>(a.xyz, 1.0);
    var cb = globals.view_proj * vec4<f32>(b.xyz, 1.0);
    // Cut the segment at the near plane (depth 0, where clip z = 0) so that an end
    // behind the eye does not flip the quad.
    if (ca.z < 0.0 && cb.z < 0.0) {
        out.clip = vec4<f32>(0.0, 0.0, -1.0, 1.0);
        return out;
    }
    if (ca.z < 0.0) {
        ca = mix(ca, cb, ca.z / (ca.z - cb.z));
    } else if (cb.z < 0.0) {
        cb = mix(cb, ca, cb.z / (cb.z - ca.z));
    }
    let half_size = globals.viewport.xy * 0.5;
    let sa = ca.xy / ca.w * half_size;
    let sb = cb.xy / cb.w * half_size;
    var along = sb - sa;
    if (dot(along, along) < 1e-8) {
        along = vec2<f32>(1.0, 0.0);
    }
    along = normalize(along);
    let across = vec2<f32>(-along.y, along.x);
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(0.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(0.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0),
    );
    let corner = corners[i];
    let half_width = 0.5 * a.w * globals.viewport.y / 720.0;
    var c = ca;
    var cap = -1.0;
    if (corner.x > 0.5) {
        c = cb;
        cap = 1.0;
    }
    let offset = (across * corner.y + along * cap) * half_width / half_size;
    out.clip = vec4<f32>(c.xy + offset * c.w, c.z, c.w);
    return out;
}

@fragment
fn fs_line(in: LineOut) -> @location(0) vec4<f32> {
    return in.color;
}
