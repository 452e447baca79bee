// A hair fibre's width as drawn, from the hair type's cross-section the server sends in SCENE (the physics'
// presets, crates/strand/src/hair_type.rs; the viewer keeps no copy). A fibre with an elliptical section
// (major-axis diameter D, ellipticity e = major / minor axis) lies at a random angle about its axis, so it
// covers on average its mean width, perimeter / pi (Cauchy's formula for a convex section), with Ramanujan's
// perimeter of the ellipse of semi-axes a = D / 2, b = D / (2 e):
//   width = 3 (a + b) - sqrt((3 a + b) (a + 3 b)).
// A round fibre (e = 1) is D wide; a Caucasian fibre (80 um, e = 1.4) about 68.9 um.

/** Mean projected width (m) of a fibre of major-axis diameter `diameter` (m) and ellipticity `ellipticity` (>= 1). */
export function meanFibreWidth(diameter: number, ellipticity: number): number {
  if (!(diameter > 0 && Number.isFinite(diameter)) || !(ellipticity >= 1 && Number.isFinite(ellipticity))) {
    throw new Error(`a fibre section needs a diameter > 0 m and an ellipticity >= 1, got ${diameter} m and ${ellipticity}`);
  }
  const a = diameter / 2, b = diameter / (2 * ellipticity);
  return 3 * (a + b) - Math.sqrt((3 * a + b) * (a + 3 * b));
}
