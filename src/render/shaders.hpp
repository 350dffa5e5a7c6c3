#pragma once
// GLSL 3.30 core sources of the renderer (private to src/render). Programs are assembled as
// "#version 330 core" + "#define PER_FRAGMENT 0|1" + the stage source. The coat's lighting
// (kCoatShading) runs per vertex (PER_FRAGMENT 0: the thesis' per-vertex evaluation of the projected
// angles, 7.1.3, and the fast default) or per fragment (PER_FRAGMENT 1).
namespace pteryla::render::shaders {

// Streit 2003, 7.1.3: the Poulin-Fournier table stores D and S over (alpha_L, alpha_V), the angles
// of the projected light / view from the barbule binormal B = T x N, and the radiance is
// albedo * E * |L'| * D (brdf_table.hpp). Two look-ups per light, one for the barbules on each side
// of the barb. Light directions arrive normalised; uBarbuleCosSin = (cos, sin) of the barbule angle.
inline constexpr const char* kCoatShading = R"GLSL(
uniform sampler2D uBrdfTex;
uniform vec3 uEye;
uniform vec3 uAmbient;
uniform int uLightCount;
uniform vec3 uLightDir[4];
uniform vec3 uLightColor[4];
uniform int uUseBrdf;
uniform vec2 uBarbuleCosSin;
uniform float uSpecular;
uniform float uConeInv2s2;
uniform float uTranslucency;
const float kPi = 3.14159265358979;

// acos with |error| < 7e-5 rad (Abramowitz-Stegun 4.4.45 form), well below the table's pi/128 cells.
float fastAcos(float x) {
  float ax = min(abs(x), 1.0);
  float r = sqrt(1.0 - ax) * (1.5707288 + ax * (-0.2121144 + ax * (0.0742610 - 0.0187293 * ax)));
  return x >= 0.0 ? r : kPi - r;
}

float projectedAngle(vec3 dir, vec3 T, vec3 B, out float len) {
  vec3 p = dir - dot(dir, T) * T;
  len = length(p);
  return len > 1e-5 ? fastAcos(dot(B, p) / len) : 0.5 * kPi;
}

// Returns the irradiance factor for the albedo (rgb of `diffuse`) and the specular radiance: from the
// ambient and lights 1..3 in diffuse / spec, from light 0 (the key light, which casts the shadows) in
// keyDiffuse / keySpec, to be scaled by its visibility.
void shadeCoat(vec3 pos, vec3 normal, vec3 tangent, out vec3 diffuse, out vec3 spec, out vec3 keyDiffuse,
               out vec3 keySpec) {
  vec3 V = normalize(uEye - pos);
  vec3 N = normalize(normal);
  if (dot(N, V) < 0.0) N = -N;
  diffuse = uAmbient;
  spec = vec3(0.0);
  keyDiffuse = vec3(0.0);
  keySpec = vec3(0.0);
  vec3 T = tangent - dot(tangent, N) * N;
  float lenT = length(T);
  bool aniso = uUseBrdf != 0 && lenT > 1e-4;
  vec3 Tb0 = vec3(1.0, 0.0, 0.0), Tb1 = Tb0;
  if (aniso) {
    T /= lenT;
    vec3 side = cross(N, T);
    Tb0 = uBarbuleCosSin.x * T + uBarbuleCosSin.y * side;
    Tb1 = uBarbuleCosSin.x * T - uBarbuleCosSin.y * side;
  }
  for (int i = 0; i < uLightCount; ++i) {
    vec3 L = uLightDir[i];
    float nl = dot(N, L);
    vec3 d = vec3(0.0), sp = vec3(0.0);
    if (nl <= 0.0) {
      d = uLightColor[i] * (uTranslucency * -nl);
    } else if (!aniso) {
      d = uLightColor[i] * nl;
    } else {
      float lenL0, lenL1, lenV;
      vec3 B0 = cross(Tb0, N), B1 = cross(Tb1, N);
      vec2 c0 = vec2(projectedAngle(L, Tb0, B0, lenL0), projectedAngle(V, Tb0, B0, lenV)) / kPi;
      vec2 c1 = vec2(projectedAngle(L, Tb1, B1, lenL1), projectedAngle(V, Tb1, B1, lenV)) / kPi;
      vec2 ds0 = textureLod(uBrdfTex, c0, 0.0).rg;
      vec2 ds1 = textureLod(uBrdfTex, c1, 0.0).rg;
      float a0 = dot(L, Tb0) + dot(V, Tb0), a1 = dot(L, Tb1) + dot(V, Tb1);
      d = uLightColor[i] * (0.5 * (lenL0 * ds0.r + lenL1 * ds1.r));
      sp = uLightColor[i] * (0.5 * uSpecular *
           (lenL0 * ds0.g * exp(-a0 * a0 * uConeInv2s2) + lenL1 * ds1.g * exp(-a1 * a1 * uConeInv2s2)));
    }
    if (i == 0) {
      keyDiffuse = d;
      keySpec = sp;
    } else {
      diffuse += d;
      spec += sp;
    }
  }
}
)GLSL";

// The key light's shadow map (shadow_pass.cpp: an orthographic depth map of the skin and the alpha-tested
// coat from light 0). vShadowPos is the fragment's light clip position, pushed off its surface along the
// normal in the vertex shader. Four bilinear depth comparisons (hardware PCF) half a texel apart give a
// soft edge about two texels wide. Returns the key light's visibility in [1 - uShadowStrength, 1].
inline constexpr const char* kShadowLookup = R"GLSL(
uniform sampler2DShadow uShadowMap;
uniform int uShadows;
uniform float uShadowStrength;
uniform float uShadowTexel;
float keyVisibility(vec4 shadowPos) {
  if (uShadows == 0) return 1.0;
  vec3 p = shadowPos.xyz / shadowPos.w * 0.5 + 0.5;
  if (p.x <= 0.0 || p.y <= 0.0 || p.x >= 1.0 || p.y >= 1.0 || p.z >= 1.0) return 1.0;
  float h = 0.5 * uShadowTexel;
  float lit = 0.25 * (texture(uShadowMap, vec3(p.xy + vec2(-h, -h), p.z)) + texture(uShadowMap, vec3(p.xy + vec2(h, -h), p.z)) +
                      texture(uShadowMap, vec3(p.xy + vec2(-h, h), p.z)) + texture(uShadowMap, vec3(p.xy + vec2(h, h), p.z)));
  return 1.0 - uShadowStrength * (1.0 - lit);
}

// Exposure and tone curve (RenderSettings::exposure, filmic), applied to skin and feather colours before
// blending. Filmic: Narkowicz's fit of the ACES reference curve.
uniform float uExposureScale;
uniform int uFilmic;
vec3 toneMap(vec3 c) {
  c *= uExposureScale;
  if (uFilmic != 0) c = clamp((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14), 0.0, 1.0);
  return c;
}
)GLSL";

// Vertex attributes of every vertex shader. Locations match renderer_impl.hpp's Attr enum.
inline constexpr const char* kMeshAttributes = R"GLSL(
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec3 aTangent;
layout(location = 3) in vec2 aUvGlobal;
layout(location = 4) in vec2 aUvBarb;
layout(location = 5) in vec2 aUvGrowth;
layout(location = 6) in float aAlpha;
layout(location = 7) in float aSheath;
layout(location = 8) in float aBarbCount;
uniform int uColorUv;
// The texture coordinates of the colour texture (FeatherMaterial::colorUv) and of the barb alpha mask,
// repeated barbCount times across a polygon.
vec2 colorUv() { return uColorUv == 1 ? aUvBarb : (uColorUv == 2 ? aUvGrowth : aUvGlobal); }
vec2 alphaUv() { return vec2(aUvBarb.x * max(aBarbCount, 1.0), aUvBarb.y); }
)GLSL";

// A feather fragment's opacity, the same in the colour pass and the shadow map: vertex alpha x the colour
// texture's alpha x the barb alpha mask, blended toward the opaque sheath (8.1).
inline constexpr const char* kFeatherAlpha = R"GLSL(
uniform sampler2D uAlphaTex;
uniform int uUseAlphaTex;
float featherAlpha(float alpha, float textureAlpha, vec2 uvAlpha, float sheath) {
  float a = alpha * textureAlpha;
  if (uUseAlphaTex != 0) a *= texture(uAlphaTex, uvAlpha).r;
  return mix(a, 1.0, sheath);
}
)GLSL";

// Shared by skin and coat (after kMeshAttributes).
inline constexpr const char* kMeshVertex = R"GLSL(
uniform mat4 uViewProj;
uniform int uIsCoat;
uniform mat4 uLightViewProj;
uniform vec3 uShadowLightDir;
uniform float uShadowNormalOffset;
out vec3 vPos;
out vec4 vShadowPos;
out vec3 vNormal;
out vec2 vUvColor;
out vec2 vUvAlpha;
out float vAlpha;
out float vSheath;
#if PER_FRAGMENT
out vec3 vTangent;
#else
out vec3 vDiffuse;
out vec3 vSpec;
out vec3 vKeyDiffuse;
out vec3 vKeySpec;
#endif
void main() {
  vPos = aPos;
  vNormal = aNormal;
  vUvColor = colorUv();
  vUvAlpha = alphaUv();
  vAlpha = aAlpha;
  vSheath = clamp(aSheath, 0.0, 1.0);
#if PER_FRAGMENT
  vTangent = aTangent;
#else
  if (uIsCoat != 0) {
    shadeCoat(aPos, aNormal, aTangent, vDiffuse, vSpec, vKeyDiffuse, vKeySpec);
  } else {
    vDiffuse = vec3(0.0);
    vSpec = vec3(0.0);
    vKeyDiffuse = vec3(0.0);
    vKeySpec = vec3(0.0);
  }
#endif
  // Off the surface toward the key light's side (a vane is lit from either side), so the surface does
  // not shadow itself.
  vec3 n = normalize(aNormal);
  vec3 offset = (dot(n, uShadowLightDir) >= 0.0 ? n : -n) * uShadowNormalOffset;
  vShadowPos = uLightViewProj * vec4(aPos + offset, 1.0);
  gl_Position = uViewProj * vec4(aPos, 1.0);
}
)GLSL";

inline constexpr const char* kSkinFragment = R"GLSL(
in vec3 vPos;
in vec4 vShadowPos;
in vec3 vNormal;
uniform vec3 uEye;
uniform vec3 uSkinColor;
uniform vec3 uAmbient;
uniform int uLightCount;
uniform vec3 uLightDir[4];
uniform vec3 uLightColor[4];
out vec4 oColor;
void main() {
  vec3 V = normalize(uEye - vPos);
  vec3 N = normalize(vNormal);
  if (dot(N, V) < 0.0) N = -N;
  vec3 light = uAmbient;
  for (int i = 0; i < uLightCount; ++i)
    light += uLightColor[i] * max(dot(N, uLightDir[i]), 0.0) * (i == 0 ? keyVisibility(vShadowPos) : 1.0);
  oColor = vec4(toneMap(uSkinColor * light), 1.0);
}
)GLSL";

// Colour pattern x base colour, barb alpha mask repeated barbCount times, sheath blend (8.1).
inline constexpr const char* kCoatFragment = R"GLSL(
in vec3 vPos;
in vec4 vShadowPos;
in vec3 vNormal;
in vec2 vUvColor;
in vec2 vUvAlpha;
in float vAlpha;
in float vSheath;
#if PER_FRAGMENT
in vec3 vTangent;
#else
in vec3 vDiffuse;
in vec3 vSpec;
in vec3 vKeyDiffuse;
in vec3 vKeySpec;
#endif
uniform sampler2D uColorTex;
uniform vec3 uBaseColor;
uniform vec3 uSheathColor;
out vec4 oColor;
void main() {
  vec4 tex = texture(uColorTex, vUvColor);
  float a = featherAlpha(vAlpha, tex.a, vUvAlpha, vSheath);
  if (a < 0.5 / 255.0) discard;
  vec3 albedo = mix(uBaseColor * tex.rgb, uSheathColor, vSheath);
#if PER_FRAGMENT
  vec3 diffuse, spec, keyDiffuse, keySpec;
  shadeCoat(vPos, vNormal, vTangent, diffuse, spec, keyDiffuse, keySpec);
#else
  vec3 diffuse = vDiffuse, spec = vSpec, keyDiffuse = vKeyDiffuse, keySpec = vKeySpec;
#endif
  float visible = keyVisibility(vShadowPos);
  diffuse += keyDiffuse * visible;
  spec += keySpec * visible;
  oColor = vec4(toneMap(albedo * diffuse + spec * (1.0 - vSheath)), a);
}
)GLSL";

// The shadow map pass: light clip positions; the coat's fragments are kept where the feather is opaque
// enough (the same alpha as the colour pass, thresholded at uAlphaCut), so barbs cast barb-shaped shadows.
inline constexpr const char* kDepthVertex = R"GLSL(
uniform mat4 uLightViewProj;
out vec2 vUvColor;
out vec2 vUvAlpha;
out float vAlpha;
out float vSheath;
void main() {
  vUvColor = colorUv();
  vUvAlpha = alphaUv();
  vAlpha = aAlpha;
  vSheath = clamp(aSheath, 0.0, 1.0);
  gl_Position = uLightViewProj * vec4(aPos, 1.0);
}
)GLSL";

inline constexpr const char* kDepthFragment = R"GLSL(
in vec2 vUvColor;
in vec2 vUvAlpha;
in float vAlpha;
in float vSheath;
uniform sampler2D uColorTex;
uniform float uAlphaCut;
void main() {
  float a = featherAlpha(vAlpha, texture(uColorTex, vUvColor).a, vUvAlpha, vSheath);
  if (a < uAlphaCut) discard;
}
)GLSL";

// Occlusion culling under multisampling: the farthest depth over each pixel's samples of the
// multisampled depth texture, written as the pixel's depth of a single-sample target and read back, so
// a coat triangle is dropped only where it lies behind the skin at every sample (draw_plan.hpp).
inline constexpr const char* kResolveVertex = R"GLSL(
void main() {
  vec2 p = vec2((gl_VertexID == 1) ? 3.0 : -1.0, (gl_VertexID == 2) ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
)GLSL";
inline constexpr const char* kResolveFragment = R"GLSL(
uniform sampler2DMS uDepthMS;
uniform int uSamples;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  float d = 0.0;
  for (int i = 0; i < uSamples; ++i) d = max(d, texelFetch(uDepthMS, p, i).r);
  gl_FragDepth = d;
}
)GLSL";

}  // namespace pteryla::render::shaders
