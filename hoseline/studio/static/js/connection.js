// The WebSocket to the solve loop: numbered messages out, states and errors in.
// One target ('set' message) is in flight at a time: targets given while it is (a drag's pointer moves) wait,
// merged into one, and the latest is sent as soon as the state answering the one in flight arrives, so the
// server never works on a position the pointer has already left.  Commands go at once, after any target waiting.
import { marks } from './marks.js';

export class Connection {
  /** onMessage(message): called for every message from the server; onClose(): when the socket closes. */
  constructor(onMessage, onClose) {
    this.seq = 0;
    this.sentAt = new Map();  // seq -> performance.now() of the user's event it carries (the earliest, if merged)
    this.inFlight = null;  // seq of the target sent and not yet answered
    this.pending = null;  // {message, at}: the target waiting for the one in flight to be answered
    this.onMessage = onMessage;
    this.socket = new WebSocket(`ws://${location.host}/ws`);
    this.receivedAt = 0;  // performance.now() when the last message arrived (for the benchmark's breakdown)
    this.socket.addEventListener('message', (event) => {
      this.receivedAt = performance.now();
      const message = JSON.parse(event.data);
      if (message.type === 'state') {
        marks.add('received', message.seq, this.receivedAt, message.server_seconds);
        if (this.inFlight !== null && message.seq !== null && message.seq >= this.inFlight) {
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
    if (message.type === 'set') { this.inFlight = this.seq; marks.add('sent', this.seq); }
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
