// Linear radiance to the display: exposure, the ACES filmic curve (Narkowicz's fit) and the sRGB transfer.
export const displayGLSL = /* glsl */ `
uniform float exposure;
vec3 toDisplay(vec3 c) {
  c *= exposure;
  c = clamp((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14), 0.0, 1.0);
  return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
`;
