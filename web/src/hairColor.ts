// Hair colour from melanin: the absorption coefficient of the fibre's cortex is the sum of eumelanin (brown to
// black) and pheomelanin (yellow to red) absorption, each proportional to its concentration
// (d'Eon, Francois, Hill, Letteri and Aubry 2011; Chiang, Bitterli, Tappan and Burley 2016, as in pbrt-v3):
//   sigma_a = C_eu (0.419, 0.697, 1.37) + C_pheo (0.187, 0.4, 1.05)    (RGB, per unit fibre radius)
// Concentrations are dimensionless (pbrt's units); about 0.3 eumelanin is blond, 1.3 brown, 8 black, and red
// hair is dominated by pheomelanin.

/** Eumelanin absorption per unit concentration, RGB (Chiang et al. 2016). */
export const EUMELANIN_SIGMA_A: [number, number, number] = [0.419, 0.697, 1.37];
/** Pheomelanin absorption per unit concentration, RGB (Chiang et al. 2016). */
export const PHEOMELANIN_SIGMA_A: [number, number, number] = [0.187, 0.4, 1.05];

export interface Melanin {
  /** Eumelanin concentration (dimensionless, >= 0). */
  eumelanin: number;
  /** Pheomelanin concentration (dimensionless, >= 0). */
  pheomelanin: number;
}

/** The colour presets of the viewer's "colour" menu. */
export const HAIR_COLOURS: Record<string, Melanin> = {
  blond: { eumelanin: 0.3, pheomelanin: 0.08 },
  brown: { eumelanin: 1.3, pheomelanin: 0.2 },
  black: { eumelanin: 8.0, pheomelanin: 0.0 },
  red: { eumelanin: 0.12, pheomelanin: 2.6 },
};
export const DEFAULT_HAIR_COLOUR = 'brown';

/** Absorption coefficient sigma_a (RGB, per unit fibre radius) of hair with the given melanin. */
export function sigmaFromMelanin(m: Melanin): [number, number, number] {
  if (!(m.eumelanin >= 0) || !(m.pheomelanin >= 0)) {
    throw new Error(`melanin concentrations must be >= 0, got eumelanin ${m.eumelanin}, pheomelanin ${m.pheomelanin}`);
  }
  return [0, 1, 2].map((c) => m.eumelanin * EUMELANIN_SIGMA_A[c] + m.pheomelanin * PHEOMELANIN_SIGMA_A[c]) as [number, number, number];
}
