// A Foxglove WebSocket protocol v1 client (subprotocol foxglove.websocket.v1), written from the
// public specification (github.com/foxglove/ws-protocol, docs/spec.md): JSON text messages with
// an "op" field from the server (serverInfo, status, advertise, unadvertise), binary Message
// Data frames (opcode 0x01, uint32 subscription id, uint64 timestamp, payload, little-endian),
// and the client's subscribe / unsubscribe. Only what the viewer needs.

export const SUBPROTOCOL = 'foxglove.websocket.v1';
const MESSAGE_DATA = 0x01;

export class FoxgloveClient {
  /**
   * @param {string} url ws://host:port
   * @param {object} handlers onOpen(serverInfo), onMessage(channel, payload: Uint8Array,
   *   timestampNs: bigint), onStatus(text), onClose(reason); wants(channel) -> subscribe?
   */
  constructor(url, handlers) {
    this.handlers = handlers;
    this.channels = new Map();       // channel id -> channel
    this.subscriptions = new Map();  // subscription id -> channel
    this.nextSubscription = 1;
    this.ws = new WebSocket(url, [SUBPROTOCOL]);
    this.ws.binaryType = 'arraybuffer';
    this.ws.onmessage = (event) => this.receive(event.data);
    this.ws.onclose = (event) => handlers.onClose?.(event.reason || `closed (${event.code})`);
    // A failed connection is reported by onclose too; the error event says nothing more.
    this.ws.onerror = () => {};
  }

  close() { this.ws.close(); }

  receive(data) {
    if (typeof data === 'string') return this.receiveJson(JSON.parse(data));
    const view = new DataView(data);
    if (view.byteLength < 13 || view.getUint8(0) !== MESSAGE_DATA) return;  // time etc.: unused
    const channel = this.subscriptions.get(view.getUint32(1, true));
    if (!channel) return;  // a message still in flight after unsubscribing
    this.handlers.onMessage?.(channel, new Uint8Array(data, 13), view.getBigUint64(5, true));
  }

  receiveJson(message) {
    switch (message.op) {
      case 'serverInfo':
        if (this.ws.protocol !== SUBPROTOCOL) {
          this.handlers.onStatus?.(`server chose subprotocol '${this.ws.protocol}'`);
        }
        this.handlers.onOpen?.(message);
        break;
      case 'status':
        this.handlers.onStatus?.(`${message.message}`);
        break;
      case 'advertise': {
        const subscribe = [];
        for (const channel of message.channels) {
          this.channels.set(channel.id, channel);
          if (this.handlers.wants?.(channel)) {
            const id = this.nextSubscription++;
            this.subscriptions.set(id, channel);
            subscribe.push({ id, channelId: channel.id });
          }
        }
        if (subscribe.length) this.send({ op: 'subscribe', subscriptions: subscribe });
        break;
      }
      case 'unadvertise':
        for (const id of message.channelIds) {
          this.channels.delete(id);
          for (const [sub, channel] of this.subscriptions) {
            if (channel.id === id) this.subscriptions.delete(sub);
          }
        }
        break;
      default:
        break;  // parameters, services, ...: not used by the viewer
    }
  }

  send(message) { this.ws.send(JSON.stringify(message)); }
}
