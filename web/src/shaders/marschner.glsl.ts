// Hair fibre scattering after Marschner, Jensen, Cammarano, Worley and Hanrahan, "Light scattering from human
// hair fibers" (SIGGRAPH 2003): three lobes, R (reflection at the cuticle), TT (through the fibre) and TRT
// (one internal reflection), each the product of a longitudinal Gaussian M_p(theta_h) shifted by the cuticle
// tilt and an azimuthal term N_p(phi). The azimuthal terms use the real-time fits of Karis, "Physically based
// hair shading in Unreal" (SIGGRAPH 2016 course): N_R = F cos(phi/2) / 4; N_TT and N_TRT carry the Fresnel
// factors, the absorption along the refracted path (Bravais index for the tilted incidence) and fitted
// azimuthal shapes exp(-3.65 cos phi - 3.98) and exp(17 cos phi - 16.78).
// The absorption coefficient comes from the melanin concentrations (hairColor.ts: d'Eon et al. 2011, Chiang et
// al. 2016). A water film (wetness w) adds a smooth Gaussian specular lobe at the mirror direction (Gupta and
// Magnenat-Thalmann 2007), weakens the cuticle's own reflection (water is nearly index-matched to keratin) and
// lengthens the absorbing paths (light trapped by the film), so wet hair is darker and shinier.

export const marschnerGLSL = /* glsl */ `
uniform vec3 sigmaA;          // absorption coefficient of the fibre interior per unit fibre radius (pbrt convention)
uniform float cuticleTilt;    // alpha, rad (2 to 4 deg): shifts R by -2 alpha, TT by alpha, TRT by 3 alpha
uniform float roughness;      // beta_R, rad (5 to 10 deg): width of R; TT beta_R/2, TRT 2 beta_R
uniform float fibreIndex;     // eta of keratin, 1.55
uniform float waterRoughness; // beta_W, rad: width of the water film's highlight
uniform float wetAbsorption;  // relative increase of the absorbing path length at wetness 1

const float PI = 3.14159265;

float gaussian(float beta, float x) {
  return exp(-0.5 * x * x / (beta * beta)) / (beta * 2.5066283);
}
// Schlick's approximation of the dielectric Fresnel reflectance.
float fresnel(float eta, float cosTheta) {
  float f0 = (eta - 1.0) / (eta + 1.0);
  f0 *= f0;
  float m = clamp(1.0 - cosTheta, 0.0, 1.0);
  return f0 + (1.0 - f0) * m * m * m * m * m;
}

struct HairAngles {
  float sinThetaI, sinThetaR, cosThetaI, thetaH, cosThetaD, cosPhi, cosHalfPhi;
  float cosHalfAngle; // cosine of half the angle between L and V
};
HairAngles hairAngles(vec3 T, vec3 L, vec3 V) {
  HairAngles a;
  a.sinThetaI = clamp(dot(T, L), -1.0, 1.0);
  a.sinThetaR = clamp(dot(T, V), -1.0, 1.0);
  float thetaI = asin(a.sinThetaI), thetaR = asin(a.sinThetaR);
  a.cosThetaI = cos(thetaI);
  a.thetaH = 0.5 * (thetaI + thetaR);
  a.cosThetaD = cos(0.5 * (thetaR - thetaI));
  vec3 lp = L - a.sinThetaI * T, vp = V - a.sinThetaR * T;
  a.cosPhi = clamp(dot(lp, vp) * inversesqrt(dot(lp, lp) * dot(vp, vp) + 1e-8), -1.0, 1.0);
  a.cosHalfPhi = sqrt(clamp(0.5 + 0.5 * a.cosPhi, 0.0, 1.0));
  a.cosHalfAngle = sqrt(clamp(0.5 + 0.5 * dot(L, V), 0.0, 1.0));
  return a;
}

// Per-lobe results: the fibre's lobes (without the water film), each M_p N_p (1/sr).
struct HairLobes { vec3 r; vec3 tt; vec3 trt; vec3 water; };

// widen: extra longitudinal variance (rad^2) from forward scattering through other strands (dual scattering).
HairLobes marschnerLobes(HairAngles a, vec3 sigma, float wet, float widen) {
  HairLobes o;
  float eta = fibreIndex;
  // Bravais index for the longitudinally tilted incidence, and the refracted longitudinal cosine.
  float etaP = sqrt(max(eta * eta - 1.0 + a.cosThetaD * a.cosThetaD, 1e-4)) / a.cosThetaD;
  float inv = 1.0 / etaP;
  float sinThetaT = sqrt(max(0.0, 1.0 - a.cosThetaD * a.cosThetaD)) / eta;
  float cosThetaT = sqrt(max(1e-4, 1.0 - sinThetaT * sinThetaT));
  vec3 sig = sigma * (1.0 + wetAbsorption * wet);
  float bR = sqrt(roughness * roughness + widen);
  float bTT = sqrt(0.25 * roughness * roughness + widen);
  float bTRT = sqrt(4.0 * roughness * roughness + widen);
  // R: water nearly matches keratin's index, so a soaked cuticle reflects little (Fresnel 1.55/1.33 vs 1.55/1).
  float fR = fresnel(mix(eta, eta / 1.33, wet), a.cosHalfAngle);
  o.r = vec3(gaussian(bR, a.thetaH + 2.0 * cuticleTilt) * 0.25 * a.cosHalfPhi * fR);
  // TT: offset h_TT of the ray that exits towards phi, path 2 sqrt(1 - (h/eta')^2) / cos(theta_t).
  float hTT = clamp((1.0 + inv * (0.6 - 0.8 * a.cosPhi)) * a.cosHalfPhi, 0.0, 1.0);
  float fTT = fresnel(eta, a.cosThetaD * sqrt(max(0.0, 1.0 - hTT * hTT)));
  vec3 tTT = exp(-sig * 2.0 * sqrt(max(0.0, 1.0 - hTT * hTT * inv * inv)) / cosThetaT);
  o.tt = gaussian(bTT, a.thetaH - cuticleTilt) * (1.0 - fTT) * (1.0 - fTT) * tTT * exp(-3.65 * a.cosPhi - 3.98);
  // TRT: the caustic-dominated offset h = sqrt(3)/2, path twice as long.
  float fTRT = fresnel(eta, a.cosThetaD * 0.5);
  vec3 tTRT = exp(-sig * 4.0 * sqrt(max(0.0, 1.0 - 0.75 * inv * inv)) / cosThetaT);
  o.trt = gaussian(bTRT, a.thetaH - 3.0 * cuticleTilt) * (1.0 - fTRT) * (1.0 - fTRT) * fTRT * tTRT * exp(17.0 * a.cosPhi - 16.78);
  // Water film: a smooth dielectric cylinder (no cuticle tilt), Gaussian in theta_h.
  float fW = fresnel(1.33, a.cosHalfAngle);
  o.water = vec3(wet * gaussian(waterRoughness, a.thetaH) * 0.25 * a.cosHalfPhi * fW);
  return o;
}
`;
