// The WebSocket to the solve loop: numbered messages out, states and errors in.
// One target ('set' message) is in flight at a time: targets given while it is (a drag's pointer moves) wait,
// merged into one, and the latest is sent as soon as the state answering the one in flight arrives, so the
// server never works on a position the pointer has already left.  Commands go at once, after any target waiting.
import { marks } from './marks.js';

const AWAITED_ROUND_TRIPS = 2;  // the answer to a target is awaited for this many recent round trips after sending
const AWAITED_MOST_MS = 50;  // and never longer
const ROUND_TRIP_WEIGHT = 0.2;  // of the latest round trip in the recent one (an exponential average)
const STREAM_MS = 50;  // targets sent this close after one another (3 frames at 60 Hz) are a stream

export class Connection {
  /** onMessage(message): called for every message from the server; onClose(): when the socket closes. */
  constructor(onMessage, onClose) {
    this.seq = 0;
    this.sentAt = new Map();  // seq -> performance.now() of the user's event it carries (the earliest, if merged)
    this.inFlight = null;  // seq of the target sent and not yet answered
    this.pending = null;  // {message, at}: the target waiting for the one in flight to be answered
    this.inFlightSentAt = -Infinity;  // performance.now() when the target in flight (or the last) was sent
    this.sendInterval = Infinity;  // ms between the last two targets sent
    this.roundTrip = null;  // ms from a target sent to its state received, recently (null: none yet)
    this.onMessage = onMessage;
    this.socket = new WebSocket(`ws://${location.host}/ws`);
    this.receivedAt = 0;  // performance.now() when the last message arrived (for the benchmark's breakdown)
    this.socket.addEventListener('message', (event) => {
      this.receivedAt = performance.now();
      const message = JSON.parse(event.data);
      if (message.type === 'state') {
        marks.add('received', message.seq, this.receivedAt, message.server_seconds);
        if (this.inFlight !== null && message.seq !== null && message.seq >= this.inFlight) {
          const roundTrip = this.receivedAt - this.inFlightSentAt;
          this.roundTrip = this.roundTrip === null ? roundTrip
            : (1 - ROUND_TRIP_WEIGHT) * this.roundTrip + ROUND_TRIP_WEIGHT * roundTrip;
          this.inFlight = null;
          this._sendPending();  // before the state is drawn: the server works while the page draws
        }
      }
      this.onMessage(message);
    });
    this.socket.addEventListener('close', onClose);
  }

  /** Send a message at once (a command, or a target); returns its seq.  `at`: when the user's event happened
   * (performance.now()). */
  send(message, at = performance.now()) {
    if (message.type !== 'set') this._sendPending();  // commands keep their order after the targets given before
    this.seq += 1;
    this.sentAt.set(this.seq, at);
    this.socket.send(JSON.stringify({ ...message, seq: this.seq }));
    if (message.type === 'set') {
      const now = performance.now();
      this.sendInterval = now - this.inFlightSentAt;
      Object.assign(this, { inFlight: this.seq, inFlightSentAt: now });
      marks.add('sent', this.seq);
    }
    return this.seq;
  }

  /** Send a target now, or, while another is in flight, keep it (merged with any kept before) until that one is
   * answered. */
  sendTarget(message, at = performance.now()) {
    if (this.inFlight === null) return this.send(message, at);
    this.pending = this.pending === null ? { message, at } : { message: merged(this.pending.message, message), at: this.pending.at };
    return null;
  }

  _sendPending() {
    if (this.pending === null) return;
    const { message, at } = this.pending;
    this.pending = null;
    this.send(message, at);
  }

  /** The send times of every seq up to `seq`, forgotten once taken (for the latency figures). */
  takeUpTo(seq) {
    const times = [];
    for (const [key, time] of this.sentAt) {
      if (key <= seq) { times.push(time); this.sentAt.delete(key); }
    }
    return times;
  }

  /** performance.now() until which the state answering the target in flight is expected (AWAITED_ROUND_TRIPS
   * recent round trips after it was sent, at most AWAITED_MOST_MS), or null: none in flight, or no round trip yet. */
  get awaitedUntil() {
    if (this.inFlight === null || this.roundTrip === null) return null;
    return this.inFlightSentAt + Math.min(AWAITED_MOST_MS, AWAITED_ROUND_TRIPS * this.roundTrip);
  }

  /** Whether targets are sent as a stream: the last two STREAM_MS apart at most, the last one STREAM_MS ago at most. */
  get streaming() {
    return this.sendInterval <= STREAM_MS && performance.now() - this.inFlightSentAt <= STREAM_MS;
  }

  /** Whether a message is unanswered or a target waits to be sent. */
  get waiting() { return this.sentAt.size > 0 || this.pending !== null; }
}

/** One target for two, as the server's inbox merges them: the newer's values, the older's where the newer leaves a
 * part out (a slider moved while a fitting is dragged: both kept). */
function merged(older, newer) {
  const both = { ...older, ...newer };
  if (older.hose && newer.hose) both.hose = { ...older.hose, ...newer.hose };
  if (newer.pose === undefined && (newer.start || newer.end || newer.clips)) delete both.pose;
  return both;
}
