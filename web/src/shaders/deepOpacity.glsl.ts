// Deep opacity maps (Yuksel and Keyser, "Deep opacity maps", Eurographics 2008) from the key light:
//  pass 1 renders the depth z0 of the first hair or body surface seen from the light (depth texture);
//  pass 2 renders every (sub-sampled) strand again with additive blending into four layers that start at z0
//  and end domLayers.x..w behind it: layer k counts the hairs crossed within [z0, z0 + d_k] (cumulative);
//  the lookup interpolates the count at a point's depth between the layer ends and turns it into the
//  expected number of strand hits towards the light n = count * coverage (a texel-wide ray meets a hair of
//  diameter D crossing the texel with probability D / texel width).
// Both passes deform the strands with the same code as the lit pass (hairDeform.glsl.ts).

export const domLookupGLSL = /* glsl */ `
uniform sampler2D domDepth;     // light-space depth [0,1] of the first surface per texel
uniform sampler2D domOpacity;   // hairs crossed within each layer (cumulative from z0), rgba = layers 1..4
uniform mat4 domMatrix;         // world -> light clip space (orthographic)
uniform vec4 domLayers;         // layer ends behind the first surface, m
uniform float domDepthRange;    // far - near of the light camera, m
uniform float domCoverage;      // hair diameter / texel width: hits per hair crossing a texel
uniform float domBias;          // m, against self-shadowing of the first layer

// Expected number of hair hits between p (world, m) and the key light.
float strandsTowardsLight(vec3 p) {
  vec4 c = domMatrix * vec4(p, 1.0);
  vec3 s = c.xyz / c.w * 0.5 + 0.5;
  if (any(lessThan(s.xy, vec2(0.0))) || any(greaterThan(s.xy, vec2(1.0)))) return 0.0;
  float z0 = texture(domDepth, s.xy).r;
  float dz = (s.z - z0) * domDepthRange - domBias;
  if (dz <= 0.0) return 0.0;
  vec4 o = texture(domOpacity, s.xy);
  float count;
  if (dz < domLayers.x) count = o.r * dz / domLayers.x;
  else if (dz < domLayers.y) count = mix(o.r, o.g, (dz - domLayers.x) / (domLayers.y - domLayers.x));
  else if (dz < domLayers.z) count = mix(o.g, o.b, (dz - domLayers.y) / (domLayers.z - domLayers.y));
  else if (dz < domLayers.w) count = mix(o.b, o.a, (dz - domLayers.z) / (domLayers.w - domLayers.z));
  else count = o.a;
  return count * domCoverage;
}
`;

/** Pass 1 fragment shader: depth only (the colour is not written); cut parts are skipped. */
export const domDepthFragment = /* glsl */ `
varying float vCut;
void main() {
  if (vCut > 0.0) discard;
  gl_FragColor = vec4(1.0);
}
`;

/** Pass 2 fragment shader: adds the fragment's weight to the layers it lies in. */
export const domOpacityFragment = /* glsl */ `
uniform sampler2D domDepth;
uniform vec4 domLayers;
uniform float domDepthRange;
uniform float domResolution;
uniform float domWeight;   // hairs one fragment stands for (render strand's hairs x sub-sampling stride)
varying float vCut;
void main() {
  if (vCut > 0.0) discard;
  float z0 = texture(domDepth, gl_FragCoord.xy / domResolution).r;
  float dz = (gl_FragCoord.z - z0) * domDepthRange;
  gl_FragColor = domWeight * vec4(lessThan(vec4(dz), domLayers));
}
`;
