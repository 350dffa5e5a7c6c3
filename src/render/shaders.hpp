#pragma once
// GLSL 3.30 core sources of the renderer (private to src/render).
namespace pteryla::render::shaders {

// Shared by skin and coat. Attribute locations match renderer.cpp's Attr enum.
inline constexpr const char* kMeshVertex = R"GLSL(#version 330 core
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec3 aTangent;
layout(location = 3) in vec2 aUvGlobal;
layout(location = 4) in vec2 aUvBarb;
layout(location = 5) in vec2 aUvGrowth;
layout(location = 6) in float aAlpha;
layout(location = 7) in float aSheath;
layout(location = 8) in float aBarbCount;
uniform mat4 uViewProj;
uniform int uColorUv;
out vec3 vPos;
out vec3 vNormal;
out vec3 vTangent;
out vec2 vUvColor;
out vec2 vUvAlpha;
out float vAlpha;
out float vSheath;
void main() {
  vPos = aPos;
  vNormal = aNormal;
  vTangent = aTangent;
  vUvColor = uColorUv == 1 ? aUvBarb : (uColorUv == 2 ? aUvGrowth : aUvGlobal);
  vUvAlpha = vec2(aUvBarb.x * max(aBarbCount, 1.0), aUvBarb.y);
  vAlpha = aAlpha;
  vSheath = clamp(aSheath, 0.0, 1.0);
  gl_Position = uViewProj * vec4(aPos, 1.0);
}
)GLSL";

inline constexpr const char* kSkinFragment = R"GLSL(#version 330 core
in vec3 vPos;
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
  for (int i = 0; i < uLightCount; ++i) light += uLightColor[i] * max(dot(N, normalize(uLightDir[i])), 0.0);
  oColor = vec4(uSkinColor * light, 1.0);
}
)GLSL";

// Streit 2003, 7.1.3: colour pattern x base colour, barb alpha mask, and two look-ups in the
// Poulin-Fournier table, one for the barbules on each side of the barb. The table stores D and S
// over (alpha_L, alpha_V) = angles of the projected light / view from the barbule binormal
// B = T x N; radiance = albedo * E * |L'| * D (see brdf_table.hpp).
inline constexpr const char* kCoatFragment = R"GLSL(#version 330 core
in vec3 vPos;
in vec3 vNormal;
in vec3 vTangent;
in vec2 vUvColor;
in vec2 vUvAlpha;
in float vAlpha;
in float vSheath;
uniform sampler2D uColorTex;
uniform sampler2D uAlphaTex;
uniform sampler2D uBrdfTex;
uniform vec3 uEye;
uniform vec3 uAmbient;
uniform int uLightCount;
uniform vec3 uLightDir[4];
uniform vec3 uLightColor[4];
uniform int uUseAlphaTex;
uniform int uUseBrdf;
uniform vec3 uBaseColor;
uniform vec3 uSheathColor;
uniform float uBarbuleAngle;
uniform float uSpecular;
uniform float uConeSigma;
uniform float uTranslucency;
out vec4 oColor;
const float kPi = 3.14159265358979;

float projectedAngle(vec3 dir, vec3 T, vec3 B, out float len) {
  vec3 p = dir - dot(dir, T) * T;
  len = length(p);
  return len > 1e-5 ? acos(clamp(dot(B, p) / len, -1.0, 1.0)) : 0.5 * kPi;
}

void main() {
  vec4 tex = texture(uColorTex, vUvColor);
  float a = vAlpha * tex.a;
  if (uUseAlphaTex != 0) a *= texture(uAlphaTex, vUvAlpha).r;
  vec3 albedo = mix(uBaseColor * tex.rgb, uSheathColor, vSheath);
  a = mix(a, 1.0, vSheath);
  if (a < 0.5 / 255.0) discard;

  vec3 V = normalize(uEye - vPos);
  vec3 N = normalize(vNormal);
  if (dot(N, V) < 0.0) N = -N;
  vec3 T = vTangent - dot(vTangent, N) * N;
  float lenT = length(T);
  bool aniso = uUseBrdf != 0 && lenT > 1e-4;
  T = aniso ? T / lenT : vec3(1.0, 0.0, 0.0);
  vec3 side = cross(N, T);
  vec3 Tb0 = cos(uBarbuleAngle) * T + sin(uBarbuleAngle) * side;
  vec3 Tb1 = cos(uBarbuleAngle) * T - sin(uBarbuleAngle) * side;
  float inv2s2 = 1.0 / (2.0 * uConeSigma * uConeSigma);

  vec3 diffuse = uAmbient;
  vec3 spec = vec3(0.0);
  for (int i = 0; i < uLightCount; ++i) {
    vec3 L = normalize(uLightDir[i]);
    float nl = dot(N, L);
    if (nl <= 0.0) {
      diffuse += uLightColor[i] * (uTranslucency * -nl);
      continue;
    }
    if (!aniso) {
      diffuse += uLightColor[i] * nl;
      continue;
    }
    float dsum = 0.0, ssum = 0.0;
    for (int k = 0; k < 2; ++k) {
      vec3 Tb = k == 0 ? Tb0 : Tb1;
      vec3 B = cross(Tb, N);
      float lenL, lenV;
      float aL = projectedAngle(L, Tb, B, lenL);
      float aV = projectedAngle(V, Tb, B, lenV);
      vec2 ds = textureLod(uBrdfTex, vec2(aL, aV) / kPi, 0.0).rg;
      float along = dot(L, Tb) + dot(V, Tb);
      dsum += lenL * ds.r;
      ssum += lenL * ds.g * exp(-along * along * inv2s2);
    }
    diffuse += uLightColor[i] * (0.5 * dsum);
    spec += uLightColor[i] * (0.5 * ssum * uSpecular);
  }
  oColor = vec4(albedo * diffuse + spec * (1.0 - vSheath), a);
}
)GLSL";

}  // namespace pteryla::render::shaders
