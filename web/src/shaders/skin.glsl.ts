// Skin, eyes and clothes of the person. Skin: a wrapped Lambert term whose wrap is wider in red than in blue
// (a cheap stand-in for subsurface scattering: light bleeds past the terminator reddened), a GGX specular lobe
// for the skin's oily film, hemisphere ambient, and the hair's and the body's shadows from the deep opacity
// maps. vMaterial selects the surface: 0 skin, 1 cloth (matte, no wrap), 2 eye (glossy cornea).

export const skinVertex = /* glsl */ `
attribute vec3 albedo;    // linear RGB
attribute float surface;  // 0 skin, 1 cloth, 2 eye
attribute float brow;     // eyebrow weight [0,1]
uniform vec3 browColour;  // the hair's rough albedo, linear RGB
varying vec3 vNormal;
varying vec3 vPosition;
varying vec3 vAlbedo;
varying float vSurface;
void main() {
  vec4 w = modelMatrix * vec4(position, 1.0);
  vPosition = w.xyz;
  vNormal = normalize(mat3(modelMatrix) * normal);
  vAlbedo = mix(albedo, browColour, brow);
  vSurface = surface;
  gl_Position = projectionMatrix * viewMatrix * w;
}
`;

export const skinFragmentBody = /* glsl */ `
uniform vec3 lightDirection;
uniform vec3 lightColor;
uniform vec3 skyColor;
uniform vec3 groundColor;
uniform vec3 cameraPos;
uniform vec3 scatterWrap;   // per-channel wrap of the diffuse term (skin), dimensionless
varying vec3 vNormal;
varying vec3 vPosition;
varying vec3 vAlbedo;
varying float vSurface;
const float PI_S = 3.14159265;
float ggx(float nh, float a) {
  float a2 = a * a, d = nh * nh * (a2 - 1.0) + 1.0;
  return a2 / (PI_S * d * d);
}
void main() {
  vec3 N = normalize(vNormal);
  vec3 L = normalize(lightDirection);
  vec3 V = normalize(cameraPos - vPosition);
  vec3 H = normalize(L + V);
  float nl = dot(N, L);
  float shadow = exp(-strandsTowardsLight(vPosition + N * 0.001));
  bool cloth = vSurface > 0.5 && vSurface < 1.5;
  bool eye = vSurface > 1.5;
  vec3 wrap = cloth || eye ? vec3(0.0) : scatterWrap;
  vec3 diffuse = clamp((vec3(nl) + wrap) / ((1.0 + wrap) * (1.0 + wrap)), 0.0, 1.0) * vAlbedo / PI_S;
  float rough = eye ? 0.08 : (cloth ? 0.8 : 0.42);
  float f0 = cloth ? 0.02 : 0.028;
  float nh = max(dot(N, H), 0.0), nv = max(dot(N, V), 1e-3);
  float F = f0 + (1.0 - f0) * pow(1.0 - max(dot(H, V), 0.0), 5.0);
  float spec = ggx(nh, rough * rough) * F / (4.0 * nv * max(nl, 1e-3) + 1e-3) * max(nl, 0.0);
  vec3 c = lightColor * shadow * (diffuse + vec3(spec));
  // Hemisphere ambient; the shadow term darkens it a little (the hair blocks part of the sky too).
  c += vAlbedo * mix(groundColor, skyColor, 0.5 + 0.5 * N.z) * (0.55 + 0.45 * shadow) / PI_S;
  gl_FragColor = vec4(toDisplay(c), 1.0);
}
`;
