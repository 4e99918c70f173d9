#include "shaders.hpp"

namespace vitreo::render::shaders {

// Scene vertex shader. Positions arrive in the mesh's model space (eye frame for tissue), are placed
// by u_model (rigid instruments), and are also projected into the light pipe's clip space for the
// shadow map lookup. The haze is computed per vertex (like classic per-vertex fog): it varies
// smoothly over a surface, and per fragment it cost a sqrt and an exp on every pixel of llvmpipe.
const char* const kSceneVertex = R"(#version 450 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
layout(location = 3) in float a_detachment;
layout(location = 4) in float a_highlight;
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
out float v_highlight;
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
  v_highlight = a_highlight;
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
// below (prepended by scene_fragment_source()), instead of branching on uniforms: llvmpipe executes
// both sides of a uniform branch under a mask, so an "uber-shader" paid for every feature on every
// fragment (measured: 3–4× the per-fragment cost of a plain Blinn-Phong shader). GPUs like it too.
//   MATERIAL  MaterialKind order (0 retina, 1 choroid, 2 static, 3 membrane, 4 gel, 5 instrument,
//             6 guide, 7 glow), 8 = the fluid–gas interface disc
//   LIGHT     a primary light (light pipe, else chandelier)     SHADOWS  its shadow map is bound
//   LIGHT2    a second, unshadowed light (the chandelier beside a light pipe)
//   GAS       a fluid–gas level exists           TEXTURE  the mesh has a texture
//   BURNS     the mesh has a burn texture        FLAT     one normal per triangle (F2)
const char* const kSceneFragmentBody = R"(
in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
in vec4 v_light_clip;
in float v_detachment;
in float v_highlight;
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
uniform vec3 u_light2_position;
uniform vec3 u_light2_direction;
uniform float u_light2_cos_outer;
uniform float u_light2_cos_inner;
uniform float u_light2_intensity;
uniform float u_light2_range;

uniform vec3 u_camera;
uniform float u_ambient;
uniform vec3 u_gas_up;
uniform float u_gas_level;
uniform float u_disc_radius;

const vec3 kBurnColour = vec3(0.90, 0.89, 0.84);   // coagulated retina: grey-white
const vec3 kHazeColour = vec3(0.55, 0.52, 0.48);
const vec3 kRimColour = vec3(0.94, 0.93, 0.90);    // a rolled cut edge or tear: the retina seen edge-on
const vec3 kGuideDone = vec3(0.30, 0.60, 1.00);    // the part of a guide already cut or lasered

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

// A spotlight: radiance reaching v_position and the unit direction toward the light.
float spot(vec3 position, vec3 direction, float cos_outer, float cos_inner, float intensity, float range, out vec3 l) {
  vec3 to_light = position - v_position;
  float d = length(to_light);
  l = to_light / max(d, 1e-4);
  float cone = smoothstep(cos_outer, cos_inner, dot(-l, direction));
  return intensity * cone / (1.0 + (d / range) * (d / range));
}

// What a light of `radiance` arriving from direction l adds at this fragment: diffuse (with light
// through the sheet from behind and light scattered whatever the facing) and a Blinn-Phong highlight.
vec3 shade(float radiance, vec3 l, vec3 n, vec3 v, vec3 albedo, float specular, vec3 spec_colour, float translucency, float scatter) {
  float nl = dot(n, l);
  float diffuse = max(nl, 0.0) + translucency * max(-nl, 0.0) + scatter * (1.0 - abs(nl));
#if MATERIAL == 4
  diffuse = 0.35 * scatter;  // gel: volume scattering, no surface facing
#endif
  vec3 h = normalize(l + v);
  float spec = specular * pow(max(dot(n, h), 0.0), u_shininess) * (nl > 0.0 ? 1.0 : 0.0);
  return radiance * (albedo * diffuse * 1.6 + spec_colour * spec);
}

// Cheap value noise on a lattice (membrane fibres, retina sheen): a hash per corner, smoothed.
float hash2(vec2 p) { return fract(sin(dot(p, vec2(127.1, 311.7))) * 43758.5453); }
float value_noise(vec2 p) {
  vec2 i = floor(p), f = fract(p);
  f = f * f * (3.0 - 2.0 * f);
  return mix(mix(hash2(i), hash2(i + vec2(1, 0)), f.x), mix(hash2(i + vec2(0, 1)), hash2(i + vec2(1, 1)), f.x), f.y);
}

void main() {
#if MATERIAL == 6
  // A guide drawn on the fundus: pending parts in the guide's colour, done parts blue; unlit, so the
  // task stays visible outside the light pipe's spot.
  o_colour = vec4(mix(u_base_colour, kGuideDone, clamp(v_highlight, 0.0, 1.0)), u_opacity);
  return;
#elif MATERIAL == 7
  // Light itself (aiming spot and beam, the light pipe's tip and cone): added to what is behind it,
  // brightest where seen through the most of it (face-on), fading to nothing at silhouettes, so a
  // beam or a cone of light has no hard outline.
  float through = abs(dot(normalize(v_normal), normalize(u_camera - v_position)));
  o_colour = vec4(u_base_colour * (u_opacity * clamp(v_highlight, 0.0, 4.0) * through), 1.0);
  return;
#else
  vec3 v = normalize(u_camera - v_position);
#if FLAT
  vec3 n = normalize(cross(dFdx(v_position), dFdy(v_position)));
#else
  vec3 n = normalize(v_normal);
#endif
  // Two-sided: tissue is seen from inside and out, so the normal is turned toward the viewer
  // (not chosen by winding, which the supplied meshes need not keep consistent).
  if (dot(n, v) < 0.0) n = -n;
#if GAS
  bool in_gas = dot(v_position, u_gas_up) > u_gas_level;
#endif

  vec3 albedo = u_base_colour;
  float alpha = u_opacity;
  float specular = u_specular;
  float translucency = 0.0;  // light through the sheet from behind (membranes, detached retina)
  float scatter = 0.0;       // light scattered by the tissue whatever its facing (gel)
#if MATERIAL == 0
  // Retina: a thin, nearly transparent sheet carrying the vessels (premultiplied texture) over the
  // separate choroid; detached retina is greyer and more opaque (it hides the choroid, and the
  // subretinal fluid under it tints what little shows through), its vessels move with it; a cut
  // edge or tear rolls and shows whiter.
#if TEXTURE
  vec4 vessels = texture(u_texture, v_uv);
#else
  vec4 vessels = vec4(0.0);
#endif
  float detached = u_detached ? 1.0 : clamp(v_detachment, 0.0, 1.0);
  float rim = clamp(v_highlight, 0.0, 1.0);
  vec3 tissue = mix(u_base_colour, u_detached_colour, detached);
  float tissue_alpha = mix(u_opacity, u_detached_opacity, detached);
  tissue = mix(tissue, kRimColour, 0.8 * rim);
  tissue_alpha = mix(tissue_alpha, 0.85, rim);
  float k = mix(0.95, 0.8, detached) * (1.0 - 0.7 * rim);  // vessel opacity
  float va = vessels.a * k;
  alpha = va + tissue_alpha * (1.0 - va);
  albedo = (vessels.rgb * k + tissue * tissue_alpha * (1.0 - va)) / max(alpha, 1e-4);
  translucency = 0.35 * detached;
  specular *= 1.0 + 1.5 * rim;
#elif MATERIAL == 3
  // Membranes: white-grey fibrous sheets that glisten; thin enough to glow when lit from behind.
  // (uv: fundus coordinates, 1 ≈ 66 mm: fibres ~0.3 mm apart, wrinkles ~1.5 mm.)
  float fibres = value_noise(v_uv * vec2(220.0, 60.0)) * 0.6 + value_noise(v_uv * 45.0) * 0.4;
  albedo *= 0.84 + 0.24 * fibres;
  translucency = 0.55;
  scatter = 0.3;  // thick, fibrous tissue scatters light into the view whatever its facing
#elif MATERIAL == 4
  // Vitreous gel: a faint haze the same from every side (the shells stand for a volume, so their
  // coarse outlines must not show), glowing where the light cone crosses it; stained gel carries
  // white crystals (the texture's alpha).
  alpha *= smoothstep(1.5, 5.0, length(u_camera - v_position));  // no sheet across the lens of the eye
  scatter = 1.0;  // volume scattering: the faint glow of the light cone in the gel, whatever the facing
#if TEXTURE
  vec4 stain = texture(u_texture, v_uv);  // premultiplied
  albedo = albedo * (1.0 - stain.a) + stain.rgb;
  alpha = max(alpha, stain.a * 0.9);
#endif
#elif TEXTURE
  vec4 t = texture(u_texture, v_uv);  // premultiplied (textures are uploaded so, for clean mipmaps)
  albedo *= t.rgb / max(t.a, 1e-3);
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
#if MATERIAL == 8
  // Fluid–gas interface seen from above: a faint sheet with a bright meniscus where it meets the wall.
  float meniscus = smoothstep(0.80, 0.98, length(v_position - u_gas_up * u_gas_level) / max(u_disc_radius, 1e-3));
  alpha = mix(u_opacity, 0.9, meniscus);
#elif GAS
  if (in_gas) specular *= 2.0;  // tissue under gas looks dry and glossy
#endif

  vec3 lit = albedo * u_ambient;
  vec3 haze_light = kHazeColour * u_ambient;
#if MATERIAL == 5
  vec3 spec_colour = mix(vec3(1.0), albedo, 0.4);  // metal tints its highlight
#else
  vec3 spec_colour = vec3(1.0);
#endif
#if LIGHT
  {
    vec3 l;
    float radiance = spot(u_light_position, u_light_direction, u_cos_outer, u_cos_inner, u_light_intensity, u_light_range, l);
#if SHADOWS
    // Shadowed tissue still gets the light the lit fundus scatters back into the cavity.
    radiance *= mix(0.22, 1.0, shadow_factor());
#endif
    lit += shade(radiance, l, n, v, albedo, specular, spec_colour, translucency, scatter);
    haze_light += kHazeColour * 0.12 * u_light_intensity;  // light scattered by the whole lit cavity
  }
  // Light bounced off the lit fundus: metal reflects it (instruments are not black silhouettes),
  // membranes and gel scatter it, and the meniscus of the gas bubble shines with it.
#if MATERIAL == 5
  lit += albedo * 0.5 * u_light_intensity * (0.5 + 0.5 * max(dot(n, normalize(v_position)), 0.0));  // from the wall
#elif MATERIAL == 3 || MATERIAL == 4
  lit += albedo * 0.12 * u_light_intensity;
#elif MATERIAL == 8
  lit += vec3(0.9, 0.92, 0.95) * (0.08 + 0.55 * meniscus) * u_light_intensity;
#endif
#endif
#if LIGHT2
  {
    vec3 l;
    float radiance = spot(u_light2_position, u_light2_direction, u_light2_cos_outer, u_light2_cos_inner, u_light2_intensity, u_light2_range, l);
    lit += shade(radiance, l, n, v, albedo, specular, spec_colour, translucency, scatter);
    haze_light += kHazeColour * 0.08 * u_light2_intensity;
  }
#endif
  o_colour = vec4(mix(lit, haze_light, v_haze), clamp(alpha, 0.0, 1.0));
#endif
}
)";

std::string scene_fragment_source(const FragmentVariant& v) {
  auto flag = [](const char* name, bool on) { return std::string("#define ") + name + (on ? " 1\n" : " 0\n"); };
  return "#version 450 core\n#define MATERIAL " + std::to_string(v.material) + "\n" + flag("LIGHT", v.light) +
         flag("SHADOWS", v.shadows) + flag("LIGHT2", v.light2) + flag("GAS", v.gas) + flag("TEXTURE", v.texture) +
         flag("BURNS", v.burns) + flag("FLAT", v.flat) + kSceneFragmentBody;
}

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
// focused at u_focus: coc_px = u_coc_scale·|1/z − 1/focus| (z = depth along the view axis: a lens
// focuses on a plane normal to its axis).
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
// d uv), so the burn is a circle of radius_mm on the tissue whatever the uv stretch. u_whiteness
// (0..1) is how far the coagulation has whitened; the texture is blended with MAX, so a burn that
// whitens over several frames is simply painted again brighter.
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
uniform float u_whiteness;
out vec4 o_burn;
void main() {
  vec2 d = v_uv - u_centre_uv;
  float dist_mm = sqrt(max(dot(d, u_metric * d), 0.0));
  float t = dist_mm / u_radius_mm;
  float b = (1.0 - smoothstep(0.6, 1.0, t)) * u_whiteness;  // whitish core, soft edge
  o_burn = vec4(b, 0.0, 0.0, 1.0);
}
)";

// Labels: screen-space quads (pixels of one eye, rows from the top) textured from the glyph atlas.
const char* const kTextVertex = R"(#version 450 core
layout(location = 0) in vec2 a_pixel;
layout(location = 1) in vec2 a_uv;
layout(location = 2) in vec4 a_colour;
uniform vec2 u_eye_size;
out vec2 v_uv;
out vec4 v_colour;
void main() {
  v_uv = a_uv;
  v_colour = a_colour;
  // Rows are stored top to bottom and read back as they are: image row y is GL window row y.
  gl_Position = vec4(a_pixel.x / u_eye_size.x * 2.0 - 1.0, a_pixel.y / u_eye_size.y * 2.0 - 1.0, 0.0, 1.0);
}
)";

const char* const kTextFragment = R"(#version 450 core
in vec2 v_uv;
in vec4 v_colour;
uniform sampler2D u_atlas;
out vec4 o_colour;
void main() {
  float ink = v_uv.x < 0.0 ? 1.0 : texture(u_atlas, v_uv).a;  // u < 0: a solid quad (markers, shadows)
  o_colour = vec4(v_colour.rgb, v_colour.a * ink);
}
)";

}  // namespace vitreo::render::shaders
