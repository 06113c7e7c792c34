// Colour maps along the hose: a ratio against a limit (red below 1, yellow to green from 1 to 2)
// and a diverging map for the twisting moment.  Colours are linear RGB triples in [0, 1].

const RED = [0.83, 0.18, 0.18], ORANGE = [0.96, 0.49, 0.0], YELLOW = [0.98, 0.75, 0.18], GREEN = [0.26, 0.63, 0.28];
const BLUE = [0.13, 0.4, 0.67], WHITE = [0.97, 0.97, 0.97], DARK_RED = [0.7, 0.09, 0.17];
export const PLAIN = [0.35, 0.45, 0.6];
export const RATIO_TOP = 2.0;  // ratios at or above this are green

function mix(a, b, t) { return [0, 1, 2].map((k) => a[k] + (b[k] - a[k]) * t); }

/** Colour of a value over its limit: below 1 red to orange (a violation), 1 to 2 yellow to green. */
export function ratioColour(ratio) {
  if (ratio === null || ratio === undefined || ratio >= RATIO_TOP) return GREEN;
  if (ratio < 1) return mix(RED, ORANGE, Math.max(ratio, 0));
  return mix(YELLOW, GREEN, ratio - 1);
}

/** Colour of a signed value against the largest magnitude: blue, white at zero, red. */
export function divergingColour(value, largest) {
  const t = largest > 0 ? Math.max(-1, Math.min(1, value / largest)) : 0;
  return t < 0 ? mix(WHITE, BLUE, -t) : mix(WHITE, DARK_RED, t);
}

/** Per-station colours and the legend for colour map `name` of a state message. */
export function stationColours(name, state) {
  const count = state.centerline.length;
  const fmt = (x) => (Math.abs(x) >= 100 ? x.toFixed(0) : x.toPrecision(3));
  if (name === 'clearance' && state.clearance_ratio) {
    return { colours: state.clearance_ratio.map(ratioColour), legend: { kind: 'ratio', title: 'clearance / required', low: '0', mid: '1', high: `≥ ${RATIO_TOP}` } };
  }
  if (name === 'clearance') {
    return { colours: Array(count).fill(GREEN), legend: { kind: 'ratio', title: 'no obstacles: drop an STL', low: '0', mid: '1', high: `≥ ${RATIO_TOP}` } };
  }
  if (name === 'bend') {
    const { radius, given } = state.readouts.bend_limit;  // the hose's minimum, or a typical one (studio/warnings.py)
    const title = given ? `bend radius / minimum ${fmt(radius)} mm` : `bend radius / typical minimum ${fmt(radius)} mm (none given)`;
    return { colours: state.bend_radius.map((r) => ratioColour(r === null ? null : r / radius)), legend: { kind: 'ratio', title, low: '0', mid: '1', high: `≥ ${RATIO_TOP}` } };
  }
  if (name === 'torsion') {
    const largest = Math.max(...state.twisting_moment.map(Math.abs));
    return { colours: state.twisting_moment.map((t) => divergingColour(t, largest)), legend: { kind: 'diverging', title: 'twisting moment, N·mm', low: fmt(-largest), mid: '0', high: fmt(largest) } };
  }
  return { colours: Array(count).fill(PLAIN), legend: null };
}
