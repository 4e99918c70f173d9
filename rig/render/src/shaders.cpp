#include "shaders.hpp"

namespace vitreo::render::shaders {

// Scene pass. Positions arrive in the mesh's model space (eye frame for tissue), are placed by
// u_model (rigid instruments), and are also projected into the light pipe's clip space for the
// spotlight cone and the shadow map lookup.
// Scene vertex shader. Positions arrive in the mesh's model space (eye frame for tissue), are placed
// by u_model (rigid instruments), and are also projected into the light pipe's clip space for the
// shadow map lookup. The haze is computed per vertex (like classic per-vertex fog): it varies
// smoothly over a surface, and per fragment it cost a sqrt and an exp on every pixel of llvmpipe.
const char* const kSceneVertex = R"(#version 450 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
layout(location = 3) in float a_detachment;
uniform mat4 u_model;
uniform mat4 u_view_projection;
uniform mat4 u_light_view_projection;
uniform vec3 u_camera;
uniform float u_globe_radius;
uniform float u_haze_density;
uniform bool u_gas_on;
uniform vec3 u_gas_up;
uniform float u_gas_level;
out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv;
out vec4 v_light_clip;
out float v_detachment;
out float v_haze;

// Length of the camera ray inside the globe before it reaches p: that much infusion / vitreous
// scatters light into the view. Gas scatters much less.
float haze_path(vec3 p) {
  vec3 d = p - u_camera;
  float len = length(d);
  vec3 dir = d / len;
  float b = dot(u_camera, dir);
  float c = dot(u_camera, u_camera) - u_globe_radius * u_globe_radius;
  float disc = b * b - c;
  if (disc <= 0.0) return 0.0;
  float t0 = max(-b - sqrt(disc), 0.0);
  return max(len - t0, 0.0);
}

void main() {
  v_detachment = a_detachment;
  vec4 world = u_model * vec4(a_position, 1.0);
  v_position = world.xyz;
  v_normal = mat3(u_model) * a_normal;  // rigid placements only: no inverse-transpose needed
  v_uv = a_uv;
  v_light_clip = u_light_view_projection * world;
  float path = haze_path(world.xyz);
  if (u_gas_on && dot(world.xyz, u_gas_up) > u_gas_level) path *= 0.15;
  v_haze = 1.0 - exp(-u_haze_density * path);
  gl_Position = u_view_projection * world;
}
)";

// Scene fragment shader body. It is compiled into variants, one per combination of the defines
// below (prepended by the renderer), instead of branching on uniforms: llvmpipe executes both sides
// of a uniform branch under a mask, so an "uber-shader" paid for every feature on every fragment
// (measured: 3–4× the per-fragment cost of a plain Blinn-Phong shader). On GPUs variants also help.
//   MATERIAL  MaterialKind order (0 retina … 5 instrument), 6 = the fluid–gas interface disc
//   LIGHT     the light pipe is present          SHADOWS  a shadow map is bound
//   GAS       a fluid–gas level exists           TEXTURE  the mesh has a texture
//   BURNS     the mesh has a burn texture
const char* const kSceneFragmentBody = R"(
in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
in vec4 v_light_clip;
in float v_detachment;
in float v_haze;
out vec4 o_colour;

uniform vec3 u_base_colour;
uniform float u_opacity;
uniform float u_specular;
uniform float u_shininess;
uniform bool u_detached;
uniform vec3 u_detached_colour;
uniform float u_detached_opacity;
uniform sampler2D u_texture;
uniform sampler2D u_burns;

uniform vec3 u_light_position;
uniform vec3 u_light_direction;
uniform float u_cos_outer;
uniform float u_cos_inner;
uniform float u_light_intensity;
uniform float u_light_range;
uniform sampler2DShadow u_shadow_map;

uniform vec3 u_camera;
uniform float u_ambient;
uniform vec3 u_gas_up;
uniform float u_gas_level;
uniform float u_disc_radius;

const vec3 kBurnColour = vec3(0.93, 0.91, 0.83);  // coagulated retina: whitish-yellow
const vec3 kHazeColour = vec3(0.55, 0.52, 0.48);

#if LIGHT && SHADOWS
// 0 = in shadow, 1 = lit. One depth-compare tap with linear filtering: the texture unit compares
// the 2×2 nearest depths and blends the results (percentage-closer filtering, Reeves et al. 1987),
// which softens the edge a little, as the light pipe's finite fibre does.
float shadow_factor() {
  if (v_light_clip.w <= 0.0) return 1.0;
  vec3 tc = (v_light_clip.xyz / v_light_clip.w) * 0.5 + 0.5;
  if (any(lessThan(tc, vec3(0.0))) || any(greaterThan(tc, vec3(1.0)))) return 1.0;
  return texture(u_shadow_map, tc);
}
#endif

void main() {
  vec3 v = normalize(u_camera - v_position);
  // Two-sided: tissue is seen from inside and out, so the normal is turned toward the viewer
  // (not chosen by winding, which the supplied meshes need not keep consistent).
  vec3 n = normalize(v_normal);
  if (dot(n, v) < 0.0) n = -n;
#if GAS
  bool in_gas = dot(v_position, u_gas_up) > u_gas_level;
#endif

  vec3 albedo = u_base_colour;
  float alpha = u_opacity;
  float specular = u_specular;
#if MATERIAL == 0
  // Retina: a thin, nearly transparent sheet carrying the vessels (the texture's alpha) over the
  // separate choroid; detached retina is greyish and more opaque, and its vessels move with it.
#if TEXTURE
  vec4 vessels = texture(u_texture, v_uv);
#else
  vec4 vessels = vec4(0.0);
#endif
  float detached = u_detached ? 1.0 : clamp(v_detachment, 0.0, 1.0);
  vec3 tissue = mix(u_base_colour, u_detached_colour, detached);
  float tissue_alpha = mix(u_opacity, u_detached_opacity, detached);
  albedo = mix(tissue, vessels.rgb, vessels.a);
  alpha = max(tissue_alpha, vessels.a * mix(0.95, 0.8, detached));
#elif TEXTURE
  vec4 t = texture(u_texture, v_uv);
  albedo *= t.rgb;
#if MATERIAL != 1
  alpha *= t.a;
#endif
#endif
#if BURNS
  float b = texture(u_burns, v_uv).r;
  albedo = mix(albedo, kBurnColour, b);
  alpha = max(alpha, b);
  specular *= (1.0 - 0.7 * b);  // coagulated tissue is matte
#endif
#if MATERIAL == 6
  // Fluid–gas interface seen from above: a faint sheet with a bright meniscus where it meets the wall.
  float meniscus = smoothstep(0.80, 0.98, length(v_position - u_gas_up * u_gas_level) / max(u_disc_radius, 1e-3));
  alpha = mix(u_opacity, 0.9, meniscus);
#elif GAS
  if (in_gas) specular *= 2.0;  // tissue under gas looks dry and glossy
#endif

  vec3 lit = albedo * u_ambient;
  vec3 haze_light = kHazeColour * u_ambient;
#if LIGHT
  vec3 to_light = u_light_position - v_position;
  float d = length(to_light);
  vec3 l = to_light / d;
  float cone = smoothstep(u_cos_outer, u_cos_inner, dot(-l, u_light_direction));
  float falloff = 1.0 / (1.0 + (d / u_light_range) * (d / u_light_range));
  float radiance = u_light_intensity * cone * falloff;
#if SHADOWS
  radiance *= shadow_factor();
#endif
  float diffuse = max(dot(n, l), 0.0);
  vec3 h = normalize(l + v);
  float spec = specular * pow(max(dot(n, h), 0.0), u_shininess) * (diffuse > 0.0 ? 1.0 : 0.0);
#if MATERIAL == 5
  vec3 spec_colour = mix(vec3(1.0), albedo, 0.4);  // metal tints its highlight
#else
  vec3 spec_colour = vec3(1.0);
#endif
  lit += radiance * (albedo * diffuse * 1.6 + spec_colour * spec);
  haze_light += kHazeColour * 0.12 * u_light_intensity;  // light scattered by the whole lit cavity
  // Light bounced off the lit fundus: metal reflects it (instruments are not black silhouettes),
  // and the meniscus of the gas bubble shines with it.
#if MATERIAL == 5
  lit += albedo * 0.3 * u_light_intensity * (0.4 + 0.6 * max(-n.z, 0.0));
#elif MATERIAL == 6
  lit += vec3(0.9, 0.92, 0.95) * (0.08 + 0.55 * meniscus) * u_light_intensity;
#endif
#endif
  o_colour = vec4(mix(lit, haze_light, v_haze), clamp(alpha, 0.0, 1.0));
}
)";

const char* const kShadowVertex = R"(#version 450 core
layout(location = 0) in vec3 a_position;
uniform mat4 u_model;
uniform mat4 u_light_view_projection;
void main() { gl_Position = u_light_view_projection * (u_model * vec4(a_position, 1.0)); }
)";

const char* const kShadowFragment = R"(#version 450 core
void main() {}
)";

// Depth of field of the microscope (focus pedal): a full-screen pass per eye that reads the sharp
// image from a mipmapped texture at a level chosen by the circle of confusion of a thin lens
// focused at u_focus: coc_px = u_coc_scale·|1/z − 1/focus| (z = depth along the view axis).
// Mip levels stand in for a blur kernel — cheap on llvmpipe, blockier than a real bokeh.
const char* const kCompositeVertex = R"(#version 450 core
void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));  // one triangle covering the viewport
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";

const char* const kCompositeFragment = R"(#version 450 core
uniform sampler2D u_colour;
uniform sampler2D u_depth;
uniform vec2 u_size;     // whole side-by-side image, pixels
uniform vec2 u_eye_x;    // this eye's x range, pixels
uniform float u_near;
uniform float u_far;
uniform float u_focus;
uniform float u_coc_scale;
uniform float u_max_lod;
out vec4 o_colour;
void main() {
  vec2 px = gl_FragCoord.xy;
  float d = texelFetch(u_depth, ivec2(px), 0).r;
  float z = 2.0 * u_near * u_far / (u_far + u_near - (2.0 * d - 1.0) * (u_far - u_near));
  float coc = u_coc_scale * abs(1.0 / z - 1.0 / u_focus);
  float lod = clamp(log2(max(coc, 1.0)), 0.0, u_max_lod);
  float margin = exp2(ceil(lod));  // keep the filter footprint inside this eye's half
  vec2 uv = vec2(clamp(px.x, u_eye_x.x + margin, u_eye_x.y - margin), px.y) / u_size;
  o_colour = vec4(textureLod(u_colour, uv, lod).rgb, 1.0);
}
)";

// Paints one laser burn into a mesh's burn texture (R8, in the mesh's uv space). The quad covers the
// burn's footprint in uv; u_metric is the surface metric JᵀJ of the hit triangle (J = d position /
// d uv), so the burn is a circle of radius_mm on the tissue whatever the uv stretch.
const char* const kBurnVertex = R"(#version 450 core
layout(location = 0) in vec2 a_corner;  // in [-1, 1]²
uniform vec2 u_centre_uv;
uniform vec2 u_half_extent_uv;
out vec2 v_uv;
void main() {
  v_uv = u_centre_uv + a_corner * u_half_extent_uv;
  gl_Position = vec4(v_uv * 2.0 - 1.0, 0.0, 1.0);
}
)";

const char* const kBurnFragment = R"(#version 450 core
in vec2 v_uv;
uniform vec2 u_centre_uv;
uniform mat2 u_metric;
uniform float u_radius_mm;
out vec4 o_burn;
void main() {
  vec2 d = v_uv - u_centre_uv;
  float dist_mm = sqrt(max(dot(d, u_metric * d), 0.0));
  float t = dist_mm / u_radius_mm;
  float b = 1.0 - smoothstep(0.6, 1.0, t);  // whitish core, soft edge
  o_burn = vec4(b, 0.0, 0.0, 1.0);
}
)";

}  // namespace vitreo::render::shaders
