#include "shaders.hpp"

namespace vitreo::render::shaders {

// Scene pass. Positions arrive in the mesh's model space (eye frame for tissue), are placed by
// u_model (rigid instruments), and are also projected into the light pipe's clip space for the
// spotlight cone and the shadow map lookup.
const char* const kSceneVertex = R"(#version 450 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
layout(location = 3) in float a_detachment;
uniform mat4 u_model;
uniform mat4 u_view_projection;
uniform mat4 u_light_view_projection;
out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv;
out vec4 v_light_clip;
out float v_detachment;
void main() {
  v_detachment = a_detachment;
  vec4 world = u_model * vec4(a_position, 1.0);
  v_position = world.xyz;
  v_normal = mat3(u_model) * a_normal;  // rigid placements only: no inverse-transpose needed
  v_uv = a_uv;
  v_light_clip = u_light_view_projection * world;
  gl_Position = u_view_projection * world;
}
)";

// Material kinds (MaterialKind order) plus 6 = the fluid–gas interface disc.
const char* const kSceneFragment = R"(#version 450 core
in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
in vec4 v_light_clip;
in float v_detachment;
out vec4 o_colour;

uniform int u_material;
uniform vec3 u_base_colour;
uniform float u_opacity;
uniform float u_specular;
uniform float u_shininess;
uniform bool u_detached;
uniform vec3 u_detached_colour;
uniform float u_detached_opacity;
uniform bool u_has_texture;
uniform sampler2D u_texture;
uniform bool u_has_burns;
uniform sampler2D u_burns;

uniform bool u_light_on;
uniform vec3 u_light_position;
uniform vec3 u_light_direction;
uniform float u_cos_outer;
uniform float u_cos_inner;
uniform float u_light_intensity;
uniform float u_light_range;
uniform bool u_shadows_on;
uniform sampler2DShadow u_shadow_map;
uniform float u_shadow_texel;

uniform vec3 u_camera;
uniform float u_ambient;
uniform float u_globe_radius;
uniform float u_haze_density;
uniform bool u_gas_on;
uniform vec3 u_gas_up;
uniform float u_gas_level;
uniform float u_disc_radius;

const vec3 kBurnColour = vec3(0.93, 0.91, 0.83);  // coagulated retina: whitish-yellow
const vec3 kHazeColour = vec3(0.55, 0.52, 0.48);

// 0 = in shadow, 1 = lit. Four bilinear depth-compare taps (percentage-closer filtering, Reeves et
// al. 1987) soften the shadow edge the way the light pipe's finite fibre does.
float shadow_factor() {
  if (!u_shadows_on || v_light_clip.w <= 0.0) return 1.0;
  vec3 ndc = v_light_clip.xyz / v_light_clip.w;
  vec3 tc = ndc * 0.5 + 0.5;
  if (any(lessThan(tc, vec3(0.0))) || any(greaterThan(tc, vec3(1.0)))) return 1.0;
  float s = 0.0;
  s += texture(u_shadow_map, vec3(tc.xy + vec2(-0.75, -0.75) * u_shadow_texel, tc.z));
  s += texture(u_shadow_map, vec3(tc.xy + vec2( 0.75, -0.75) * u_shadow_texel, tc.z));
  s += texture(u_shadow_map, vec3(tc.xy + vec2(-0.75,  0.75) * u_shadow_texel, tc.z));
  s += texture(u_shadow_map, vec3(tc.xy + vec2( 0.75,  0.75) * u_shadow_texel, tc.z));
  return s * 0.25;
}

// Length of the camera ray inside the globe before it reaches this fragment: that much infusion /
// vitreous scatters light into the view (haze). Gas scatters much less.
float haze_path() {
  vec3 d = v_position - u_camera;
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
  vec3 v = normalize(u_camera - v_position);
  // Two-sided: tissue is seen from inside and out, so the normal is turned toward the viewer
  // (not chosen by winding, which the supplied meshes need not keep consistent).
  vec3 n = normalize(v_normal);
  if (dot(n, v) < 0.0) n = -n;
  bool in_gas = u_gas_on && dot(v_position, u_gas_up) > u_gas_level;

  vec3 albedo = u_base_colour;
  float alpha = u_opacity;
  float specular = u_specular;
  if (u_material == 0) {
    // Retina: a thin, nearly transparent sheet carrying the vessels (the texture's alpha) over the
    // separate choroid; detached retina is greyish and more opaque, and its vessels move with it.
    vec4 vessels = u_has_texture ? texture(u_texture, v_uv) : vec4(0.0);
    float detached = u_detached ? 1.0 : clamp(v_detachment, 0.0, 1.0);
    vec3 tissue = mix(u_base_colour, u_detached_colour, detached);
    float tissue_alpha = mix(u_opacity, u_detached_opacity, detached);
    albedo = mix(tissue, vessels.rgb, vessels.a);
    alpha = max(tissue_alpha, vessels.a * mix(0.95, 0.8, detached));
  } else if (u_has_texture) {
    vec4 t = texture(u_texture, v_uv);
    albedo *= t.rgb;
    if (u_material != 1) alpha *= t.a;
  }
  if (u_has_burns) {
    float b = texture(u_burns, v_uv).r;
    albedo = mix(albedo, kBurnColour, b);
    alpha = max(alpha, b);
    specular *= (1.0 - 0.7 * b);  // coagulated tissue is matte
  }
  float meniscus = 0.0;
  if (u_material == 6) {
    // Fluid–gas interface seen from above: a faint sheet with a bright meniscus where it meets the wall.
    float r = length(v_position - u_gas_up * u_gas_level) / max(u_disc_radius, 1e-3);
    meniscus = smoothstep(0.80, 0.98, r);
    alpha = mix(u_opacity, 0.9, meniscus);
  }
  if (in_gas && u_material != 6) specular *= 2.0;  // tissue under gas looks dry and glossy

  vec3 lit = albedo * u_ambient;
  vec3 haze_light = kHazeColour * u_ambient;
  if (u_light_on) {
    vec3 to_light = u_light_position - v_position;
    float d = length(to_light);
    vec3 l = to_light / d;
    float cone = smoothstep(u_cos_outer, u_cos_inner, dot(-l, u_light_direction));
    float falloff = 1.0 / (1.0 + (d / u_light_range) * (d / u_light_range));
    float radiance = u_light_intensity * cone * falloff * shadow_factor();
    float diffuse = max(dot(n, l), 0.0);
    vec3 h = normalize(l + v);
    float spec = specular * pow(max(dot(n, h), 0.0), u_shininess) * (diffuse > 0.0 ? 1.0 : 0.0);
    vec3 spec_colour = u_material == 5 ? mix(vec3(1.0), albedo, 0.4) : vec3(1.0);  // metal tints its highlight
    lit += radiance * (albedo * diffuse * 1.6 + spec_colour * spec);
    haze_light += kHazeColour * 0.12 * u_light_intensity;  // light scattered by the whole lit cavity
    // Light bounced off the lit fundus: metal reflects it (instruments are not black silhouettes),
    // and the meniscus of the gas bubble shines with it.
    if (u_material == 5) lit += albedo * 0.3 * u_light_intensity * (0.4 + 0.6 * max(-n.z, 0.0));
    if (u_material == 6) lit += vec3(0.9, 0.92, 0.95) * (0.08 + 0.55 * meniscus) * u_light_intensity;
  }
  float path = haze_path();
  if (in_gas) path *= 0.15;
  float haze = 1.0 - exp(-u_haze_density * path);
  vec3 colour = mix(lit, haze_light, haze);
  o_colour = vec4(colour, clamp(alpha, 0.0, 1.0));
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
