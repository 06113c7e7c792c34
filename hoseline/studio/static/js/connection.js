// The WebSocket to the solve loop: numbered messages out, states and errors in.
// The server coalesces a burst of targets; each state says the last seq it has reached.

export class Connection {
  /** onMessage(message): called for every message from the server. */
  constructor(onMessage, onClose) {
    this.seq = 0;
    this.sentAt = new Map();  // seq -> performance.now() when the event was sent
    this.onMessage = onMessage;
    this.socket = new WebSocket(`ws://${location.host}/ws`);
    this.receivedAt = 0;  // performance.now() when the last message arrived (for the benchmark's breakdown)
    this.socket.addEventListener('message', (event) => {
      this.receivedAt = performance.now();
      this.onMessage(JSON.parse(event.data));
    });
    this.socket.addEventListener('close', onClose);
  }

  /** Send a message; returns its seq.  `at`: when the user's event happened (performance.now()). */
  send(message, at = performance.now()) {
    this.seq += 1;
    this.sentAt.set(this.seq, at);
    this.socket.send(JSON.stringify({ ...message, seq: this.seq }));
    return this.seq;
  }

  /** The send times of every seq up to `seq`, forgotten once taken (for the latency figures). */
  takeUpTo(seq) {
    const times = [];
    for (const [key, time] of this.sentAt) {
      if (key <= seq) { times.push(time); this.sentAt.delete(key); }
    }
    return times;
  }

  get waiting() { return this.sentAt.size > 0; }
}
