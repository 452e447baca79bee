// Weighted blended order-independent transparency (McGuire and Bavoil, "Weighted blended order-independent
// transparency", JCGT 2013) for the strands: every strand fragment of coverage a and colour c adds, whatever
// the drawing order,
//   accum.rgb += w a c,  accum.a += w a       (attachment 0)
//   reveal.r  += -ln(1 - a)                    (attachment 1: the hair lets exp(-reveal.r) of the light through)
// with a depth weight w = exp(-(d - d_ref) / falloff) (d the fragment's distance along the view, d_ref the front of
// the hair's bounding sphere), so the front layers of the hair dominate its colour as they do when strands are
// composited front to back. The composite pass lays the hair over the opaque picture:
//   colour = accum.rgb / accum.a,  alpha = 1 - exp(-reveal.r).

/** Fragment outputs of the strands' pass (GLSL 3). */
export const oitOutputGLSL = /* glsl */ `
layout(location = 0) out highp vec4 oitAccum;
layout(location = 1) out highp vec4 oitReveal;
uniform float oitDepthReference; // view distance where the weight is 1, m
uniform float oitDepthFalloff;   // the weight falls by e over this depth, m
uniform float oitMinWeight;      // smallest weight (the targets' float range)
void writeOit(vec3 colour, float coverage, float depth) {
  float a = clamp(coverage, 0.0, 0.999);
  float w = clamp(exp(-(depth - oitDepthReference) / oitDepthFalloff), oitMinWeight, 1.0);
  oitAccum = vec4(colour * (a * w), a * w);
  oitReveal = vec4(-log(1.0 - a), 0.0, 0.0, 0.0);
}
`;

/** The composite pass (a full-screen triangle blended over the opaque picture, premultiplied alpha). */
export const oitCompositeVertex = /* glsl */ `
void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }
`;
export const oitCompositeFragment = /* glsl */ `
precision highp float;
uniform sampler2D oitAccumTexture;
uniform sampler2D oitRevealTexture;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 a = texelFetch(oitAccumTexture, p, 0);
  float alpha = 1.0 - exp(-texelFetch(oitRevealTexture, p, 0).r);
  if (a.a <= 0.0 || alpha < 1e-3) discard;
  gl_FragColor = vec4(a.rgb / a.a * alpha, alpha);
}
`;
