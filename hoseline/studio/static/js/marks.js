// Timestamps of the round trip (performance.now(), ms) for the benchmark: kept only once a page script has set
// marks.list to an array; then each target sent, state received and frame drawn adds [what, seq, time, detail]
// (for a state received, the seconds the server's solver thread spent on it).
export const marks = {
  list: null,
  /** Note `what` ('sent', 'received', 'drawn') for message `seq` now, or at `at`. */
  add(what, seq, at = performance.now(), detail = null) {
    if (this.list) this.list.push([what, seq, at, detail]);
  },
};
