// Multiple scattering after Zinke, Yuksel, Weber and Keyser, "Dual scattering approximation for fast multiple
// scattering in hair" (SIGGRAPH 2008), simplified for real time:
//  - global part: light reaching a point through n strands (deep opacity maps) is forward-scattered with
//    transmittance T_f = d_f a_f^n and its longitudinal lobes widen by sigma_f^2 = n beta_f^2;
//    unscattered light arrives with probability exp(-n) (the direct shadow);
//  - local part: back-scattering among nearby strands, d_b f_back with A_b = a_b a_f^2 / (1 - a_f^2)
//    + a_b^3 a_f^2 / (1 - a_f^2)^3 (the paper's two-term series), spread about theta_h.
// a_f and a_b (one fibre's mean forward and backward attenuation) follow from the absorption: forward is
// dominated by TT along a mean chord of 1.76 radii, backward by R and TRT.
// Light hair (small absorption, a_f near 1) keeps much light deep in the volume and looks light and soft;
// dark hair (a_f small) is shaded almost only by single scattering.

export const dualScatteringGLSL = /* glsl */ `
uniform float densityForward;  // d_f, 0.7 (Zinke et al.)
uniform float densityBack;     // d_b, 0.7

struct FibreAttenuation { vec3 af; vec3 ab; vec3 Ab; };
FibreAttenuation fibreAttenuation(vec3 sigma) {
  FibreAttenuation f;
  float F0 = 0.0465; // keratin, eta 1.55
  f.af = min((1.0 - F0) * (1.0 - F0) * exp(-sigma * 1.76), vec3(0.98));
  f.ab = vec3(0.02) + (1.0 - F0) * (1.0 - F0) * 0.3 * exp(-sigma * 3.46);
  vec3 af2 = f.af * f.af, q = 1.0 - af2;
  f.Ab = f.ab * af2 / q + f.ab * f.ab * f.ab * af2 / (q * q * q);
  return f;
}

// Reflected radiance per unit irradiance (times cos theta_i) at a hair point with n strands towards the light.
// The direct and the forward-scattered light share one evaluation of the lobes, widened by the scattered
// share of the light (one evaluation per vertex keeps the cost down in software rendering).
vec3 hairRadiance(HairAngles a, vec3 sigma, float wet, float n, out vec3 highlight) {
  FibreAttenuation fa = fibreAttenuation(sigma * (1.0 + wetAbsorption * wet));
  float direct = exp(-n);
  vec3 tf = densityForward * pow(fa.af, vec3(n));
  vec3 arriving = direct + (1.0 - direct) * tf;
  float scatteredShare = (1.0 - direct) * dot(tf, vec3(0.3333)) / max(1e-4, dot(arriving, vec3(0.3333)));
  float betaF2 = 5.25 * roughness * roughness; // beta_R^2 + beta_TT^2 + beta_TRT^2
  float widen = scatteredShare * n * betaF2;
  HairLobes s = marschnerLobes(a, sigma, wet, widen);
  float cd2 = max(a.cosThetaD * a.cosThetaD, 0.05);
  float betaB = 1.5 * roughness;
  vec3 fBack = 2.0 * fa.Ab * gaussian(sqrt(betaB * betaB + widen), a.thetaH - 0.5 * cuticleTilt) / (PI * cd2);
  highlight = direct * (s.r + s.water);
  return a.cosThetaI * arriving * (s.r + s.tt + s.trt + s.water + densityBack * fBack);
}
`;
