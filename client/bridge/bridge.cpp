#include "client/bridge/bridge.hpp"

#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include <algorithm>
#include <chrono>
#include <map>
#include <mutex>
#include <sstream>

#include "client/bridge/client_queue.hpp"
#include "client/bridge/scene_json.hpp"
#include "client/bridge/web_page.hpp"
#include "client/bridge/ws_protocol.hpp"
#include "client/bridge/ws_server.hpp"
#include "client/record/raw_reader.hpp"
#include "client/record/raw_type.hpp"
#include "client/record/topic_table.hpp"
#include "common/dds/checked_type.hpp"
#include "idl/idl_text.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::bridge {

namespace fdds = eprosima::fastdds::dds;

namespace {
std::uint64_t now_wall_ns() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

/// Bytes a client's socket may hold beyond its queue before the bridge stops handing it
/// frames (websocketpp's own buffer): the queue, not the socket, absorbs a slow client.
constexpr std::size_t kSocketWatermark = 256u << 10;
/// Largest client message accepted (a subscribe to every channel is ~2 KB).
constexpr std::size_t kMaxClientMessage = 64u << 10;
/// Latched samples kept per channel: instances of a latched topic, or the last events.
constexpr std::size_t kLatchedKept = 16;
constexpr std::size_t kEventsKept = 64;

bool full_rate_only(const std::string& topic) {
  namespace t = dds::topics;
  return topic == t::kMasterCommand.name || topic == t::kSlaveState.name ||
         topic == t::kMasterState.name || topic == t::kDeviceState.name ||
         topic == t::kDeviceCommand.name;
}

bool is_bulk(const std::string& topic) {
  return topic == dds::topics::kMeshFrame.name || topic == dds::topics::kMeshFrameMonitor.name;
}

/// The channels the bridge makes itself (JSON, scene_json.hpp), after the topics' channels.
enum class Derived { kNone, kScene, kTransforms, kPlot, kEvents };
/// What a topic's samples feed into the derived channels.
enum class Feeds { kNothing, kScene, kTopology, kMesh, kSlave, kMaster, kEvents };

Feeds feeds_of(const std::string& topic) {
  namespace t = dds::topics;
  if (topic == t::kScene.name) return Feeds::kScene;
  if (topic == t::kMeshTopology.name) return Feeds::kTopology;
  if (topic == t::kMeshFrame.name) return Feeds::kMesh;
  if (topic == t::kSlaveStateView.name) return Feeds::kSlave;
  if (topic == t::kMasterStateView.name) return Feeds::kMaster;
  if (topic == t::kEvents.name) return Feeds::kEvents;
  return Feeds::kNothing;
}

/// Decodes a raw sample (encapsulation header included) as PubSub's type.
template <class PubSub>
bool decode(std::vector<std::uint8_t>& bytes, typename PubSub::type& out) {
  eprosima::fastrtps::rtps::SerializedPayload_t p;
  p.data = bytes.data();
  p.length = static_cast<std::uint32_t>(bytes.size());
  p.max_size = p.length;
  const bool ok = dds::deserialize_checked<PubSub>(p, out);
  p.data = nullptr;  // not owned
  return ok;
}

struct Latched {
  eprosima::fastrtps::rtps::InstanceHandle_t key;
  std::uint64_t receive_ns = 0;
  std::vector<std::uint8_t> bytes;
};
}  // namespace

struct Bridge::Impl {
  struct Topic {
    const record::TopicEntry* entry = nullptr;
    Channel channel;
    fdds::DataReader* reader = nullptr;
    record::RawSample scratch;
    bool bulk = false, latched = false, event_log = false;
    Derived derived = Derived::kNone;
    Feeds feeds = Feeds::kNothing;
    std::size_t bulk_index = 0;
    std::vector<Latched> kept;  // latched samples, oldest first
    std::uint64_t samples = 0;
  };
  struct Client {
    ClientId id = 0;
    ClientCounts counts;
    std::unique_ptr<ClientQueue> queue;
    std::vector<Subscription> subs;
    std::uint64_t reported_drops = 0;
  };

  dds::Participant& participant;
  BridgeOptions options;
  std::vector<std::unique_ptr<Topic>> topics;
  std::size_t bulk_channels = 0;
  std::unique_ptr<WsServer> ws;
  std::thread dds_thread;
  fdds::GuardCondition guard;
  std::atomic<bool> stopping{false}, flush_posted{false};
  mutable std::mutex mutex;  // clients, topics' kept samples and counts
  std::map<ClientId, std::unique_ptr<Client>> clients;
  std::vector<ClientCounts> departed;
  std::uint64_t samples = 0, clients_total = 0, clients_refused = 0, unauthorized = 0, pages = 0;
  int next_client_id = 1;
  std::string advertise;
  int tick = 0;
  // the derived channels' state: DDS thread only
  SceneJson scene;
  std::string json_scratch;
  std::uint64_t last_scene_ns = 0;
  std::atomic<std::uint64_t> rejected{0};  // samples that did not decode or were not valid
  std::atomic<bool> derived_now{false};    // a client subscribed to a derived channel
  std::map<Derived, Topic*> derived;

  Impl(dds::Participant& p, const BridgeOptions& o) : participant(p), options(o) {}
  void make_topics();
  void start_server(int& port_out);
  void read_loop();
  void on_sample(Topic& t, const fdds::SampleInfo& info);
  void keep_latched(Topic& t, const fdds::SampleInfo& info, std::uint64_t ns);
  void add_derived();
  void feed(Topic& t);
  void publish_derived(std::uint64_t ns);
  bool subscribed(Derived which) const;  // mutex held
  void push_json(Derived which, const std::string& json, std::uint64_t ns);
  bool on_accept();
  void on_open(ClientId id, const std::string& remote);
  void on_close(ClientId id);
  void on_message(ClientId id, bool text, const std::string& payload);
  void handle_request(Client& c, const std::string& text);
  void subscribe(Client& c, const std::vector<Subscription>& subs);
  void send_text(Client& c, const std::string& text);
  void flush_all();
  void on_timer();
  void request_flush();
};

void Bridge::Impl::make_topics() {
  std::uint32_t id = 1;
  for (const auto& e : record::known_topics()) {
    if (!options.full_rate && full_rate_only(e.name)) continue;
    auto t = std::make_unique<Topic>();
    t->entry = &e;
    t->channel.id = id++;
    t->channel.topic = e.name;
    t->channel.schema_name = e.type;
    t->channel.schema = std::string(idl::idl_text_for_type(e.type));
    t->bulk = is_bulk(e.name);
    if (t->bulk) t->bulk_index = bulk_channels++;
    t->latched = record::is_latched(e.qos);
    t->event_log = e.qos == dds::TopicQos::kEventLog;
    t->feeds = feeds_of(e.name);
    t->reader = record::create_raw_reader(participant, e, 16);
    topics.push_back(std::move(t));
  }
  add_derived();
  std::vector<Channel> channels;
  for (const auto& t : topics) channels.push_back(t->channel);
  advertise = advertise_json(channels);
}

void Bridge::Impl::add_derived() {
  struct Spec {
    Derived which;
    const char* topic;
    const char* schema_name;
    const char* schema;
    bool bulk, latched;
  };
  const Spec specs[] = {
      {Derived::kScene, "bridge/scene", "foxglove.SceneUpdate", kSceneUpdateSchema, true, false},
      {Derived::kTransforms, "bridge/transforms", "foxglove.FrameTransforms",
       kFrameTransformsSchema, true, false},
      {Derived::kPlot, "bridge/plot", "teleop.bridge.Plot", kPlotSchema, false, false},
      {Derived::kEvents, "bridge/events", "teleop.bridge.Event", kEventSchema, false, true},
  };
  for (const auto& sp : specs) {
    auto t = std::make_unique<Topic>();
    t->channel.id = static_cast<std::uint32_t>(topics.size() + 1);
    t->channel.topic = sp.topic;
    t->channel.schema_name = sp.schema_name;
    t->channel.schema = sp.schema;
    t->channel.encoding = "json";
    t->channel.schema_encoding = "jsonschema";
    t->derived = sp.which;
    t->bulk = sp.bulk;
    if (t->bulk) t->bulk_index = bulk_channels++;
    t->latched = sp.latched;
    t->event_log = sp.which == Derived::kEvents;
    derived[sp.which] = t.get();
    topics.push_back(std::move(t));
  }
}

void Bridge::Impl::feed(Topic& t) {
  bool ok = true;
  auto& b = t.scratch.bytes;
  switch (t.feeds) {
    case Feeds::kNothing:
      return;
    case Feeds::kScene: {
      SceneDescription v;
      ok = decode<SceneDescriptionPubSubType>(b, v);
      if (ok) scene.set_scene(v);
      break;
    }
    case Feeds::kTopology: {
      MeshTopology v;
      ok = decode<MeshTopologyPubSubType>(b, v) && scene.set_topology(v);
      break;
    }
    case Feeds::kMesh: {
      MeshFrame v;
      ok = decode<MeshFramePubSubType>(b, v) && scene.set_frame(v);
      break;
    }
    case Feeds::kSlave: {
      SlaveState v;
      ok = decode<SlaveStatePubSubType>(b, v) && scene.set_slave(v);
      break;
    }
    case Feeds::kMaster: {
      MasterState v;
      ok = decode<MasterStatePubSubType>(b, v) && scene.set_master(v);
      break;
    }
    case Feeds::kEvents: {
      Event v;
      ok = decode<EventPubSubType>(b, v);
      if (ok) push_json(Derived::kEvents, event_json(v), now_wall_ns());
      break;
    }
  }
  if (!ok) rejected.fetch_add(1);
}

bool Bridge::Impl::subscribed(Derived which) const {
  const std::uint32_t id = derived.at(which)->channel.id;
  for (const auto& [cid, c] : clients) {
    for (const auto& s : c->subs) {
      if (s.channel_id == id) return true;
    }
  }
  return false;
}

void Bridge::Impl::publish_derived(std::uint64_t ns) {
  // built only for channels someone reads: the scene is the bridge's largest cost; a client
  // that subscribes later makes the next take (10 ms) build it at once (derived_now)
  bool want_scene = false, want_tf = false, want_plot = false;
  {
    std::lock_guard<std::mutex> l(mutex);
    want_scene = subscribed(Derived::kScene);
    want_tf = subscribed(Derived::kTransforms);
    want_plot = subscribed(Derived::kPlot);
  }
  if (want_scene) {
    scene.scene_update(json_scratch, ns);
    push_json(Derived::kScene, json_scratch, ns);
  }
  if (want_tf) {
    scene.frame_transforms(json_scratch, ns);
    push_json(Derived::kTransforms, json_scratch, ns);
  }
  if (want_plot && scene.plot(json_scratch, ns)) push_json(Derived::kPlot, json_scratch, ns);
}

void Bridge::Impl::push_json(Derived which, const std::string& json, std::uint64_t ns) {
  Topic& t = *derived.at(which);
  const std::span<const std::uint8_t> body(reinterpret_cast<const std::uint8_t*>(json.data()),
                                           json.size());
  std::lock_guard<std::mutex> l(mutex);
  ++t.samples;
  if (t.latched) {
    // the events: the last kEventsKept
    if (t.kept.empty() || (t.event_log && t.kept.size() < kEventsKept)) {
      t.kept.emplace_back();
    } else if (t.event_log) {
      std::rotate(t.kept.begin(), t.kept.begin() + 1, t.kept.end());
    }
    t.kept.back().receive_ns = ns;
    t.kept.back().bytes.assign(body.begin(), body.end());
  }
  std::uint8_t head[kMessageDataHeader];
  for (auto& [id, c] : clients) {
    for (const auto& s : c->subs) {
      if (s.channel_id != t.channel.id) continue;
      message_data_header(head, s.id, ns);
      c->queue->push(t.bulk ? FrameClass::kBulk : FrameClass::kKept, t.bulk_index, head, body);
    }
  }
}

void Bridge::Impl::start_server(int& port_out) {
  WsHandlers h;
  h.accept = [this] { return on_accept(); };
  h.open = [this](ClientId id, const std::string& remote) { on_open(id, remote); };
  h.close = [this](ClientId id) { on_close(id); };
  h.message = [this](ClientId id, bool text, const std::string& p) { on_message(id, text, p); };
  h.tick = [this] { on_timer(); };
  h.unauthorized = [this](const std::string&) {
    std::lock_guard<std::mutex> l(mutex);
    ++unauthorized;
  };
  h.http = [this](const std::string& path) {
    HttpReply r;
    {
      std::lock_guard<std::mutex> l(mutex);
      ++pages;
    }
    if (path == "/" || path == "/index.html") {
      r.status = 200;
      r.content_type = "text/html; charset=utf-8";
      r.body = kBridgePage;
    }
    return r;
  };
  ws = std::make_unique<WsServer>(options.address, options.port, kSubprotocol, kMaxClientMessage,
                                  20, options.access, std::move(h));
  port_out = ws->port();
  ws->start();
}

bool Bridge::Impl::on_accept() {
  std::lock_guard<std::mutex> l(mutex);
  if (static_cast<int>(clients.size()) < options.max_clients) return true;
  ++clients_refused;
  return false;
}

Bridge::Bridge(dds::Participant& participant, const BridgeOptions& options)
    : impl_(std::make_unique<Impl>(participant, options)) {
  impl_->make_topics();
  impl_->start_server(port_);
  impl_->dds_thread = std::thread([this] { impl_->read_loop(); });
}

Bridge::~Bridge() {
  try {
    stop();
  } catch (...) {
  }
}

std::vector<std::string> Bridge::topics() const {
  std::vector<std::string> out;
  for (const auto& t : impl_->topics) out.push_back(t->channel.topic);
  return out;
}

void Bridge::Impl::read_loop() {
  fdds::WaitSet waitset;
  for (auto& t : topics) {
    if (t->reader) waitset.attach_condition(t->reader->get_statuscondition());
  }
  waitset.attach_condition(guard);
  fdds::ConditionSeq active;
  fdds::SampleInfo info;
  const eprosima::fastrtps::Duration_t timeout(0, 100'000'000);
  while (!stopping.load()) {
    waitset.wait(active, timeout);
    bool any = false;
    for (auto& t : topics) {
      if (!t->reader) continue;
      while (t->reader->take_next_sample(&t->scratch, &info) == ReturnCode_t::RETCODE_OK) {
        if (!info.valid_data || t->scratch.bytes.size() < 4) continue;
        on_sample(*t, info);
        feed(*t);
        any = true;
      }
    }
    const auto now = now_wall_ns();
    if (scene.ready() &&
        (derived_now.exchange(false) ||
         now - last_scene_ns >= static_cast<std::uint64_t>(scene.period_s() * 1e9))) {
      last_scene_ns = now;
      publish_derived(now);
      any = true;
    }
    if (any) request_flush();
    // take in batches: a wake-up per sample would cost the session's processes CPU
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(options.batch_ms));
  }
  for (auto& t : topics) {
    if (t->reader) waitset.detach_condition(t->reader->get_statuscondition());
  }
  waitset.detach_condition(guard);
}

void Bridge::Impl::keep_latched(Topic& t, const fdds::SampleInfo& info, std::uint64_t ns) {
  Latched* slot = nullptr;
  if (!t.event_log) {
    for (auto& k : t.kept) {
      if (k.key == info.instance_handle) slot = &k;
    }
  }
  const std::size_t cap = t.event_log ? kEventsKept : kLatchedKept;
  if (!slot && t.kept.size() < cap) {
    t.kept.emplace_back();
    slot = &t.kept.back();
  } else if (!slot) {
    // full: the oldest makes room (rotate keeps the slots' capacity)
    std::rotate(t.kept.begin(), t.kept.begin() + 1, t.kept.end());
    slot = &t.kept.back();
  }
  slot->key = info.instance_handle;
  slot->receive_ns = ns;
  slot->bytes.assign(t.scratch.bytes.begin(), t.scratch.bytes.end());
}

void Bridge::Impl::on_sample(Topic& t, const fdds::SampleInfo& info) {
  const auto ns = static_cast<std::uint64_t>(info.reception_timestamp.to_ns());
  std::lock_guard<std::mutex> l(mutex);
  ++samples;
  ++t.samples;
  if (t.latched) keep_latched(t, info, ns);
  std::uint8_t head[kMessageDataHeader];
  const std::span<const std::uint8_t> body(t.scratch.bytes);
  for (auto& [id, c] : clients) {
    for (const auto& s : c->subs) {
      if (s.channel_id != t.channel.id) continue;
      message_data_header(head, s.id, ns);
      c->queue->push(t.bulk ? FrameClass::kBulk : FrameClass::kKept, t.bulk_index, head, body);
    }
  }
}

void Bridge::Impl::request_flush() {
  if (flush_posted.exchange(true)) return;
  ws->post([this] {
    flush_posted.store(false);
    flush_all();
  });
}

void Bridge::Impl::flush_all() {
  std::lock_guard<std::mutex> l(mutex);
  for (auto& [id, c] : clients) {
    while (ws->buffered(id) < kSocketWatermark) {
      const auto* f = c->queue->front();
      if (!f) break;
      const bool ok = ws->send(id, f->data(), f->size(), false);
      c->queue->pop();
      if (!ok) break;
    }
  }
}

void Bridge::Impl::on_timer() {
  flush_all();
  if (++tick % 50 == 0) {
    // once a second: tell each client what it lost since the last report
    std::lock_guard<std::mutex> l(mutex);
    for (auto& [id, c] : clients) {
      const auto& q = c->queue->counts();
      const std::uint64_t drops = q.dropped_bulk + q.dropped_kept + q.too_large;
      if (drops == c->reported_drops) continue;
      std::ostringstream m;
      m << "teleop_bridge: this client reads too slowly: " << q.dropped_bulk << " mesh frames and "
        << q.dropped_kept << " other frames dropped so far (send queue " << c->queue->bound()
        << " bytes)";
      if (q.too_large > 0) m << ", " << q.too_large << " frames larger than the queue";
      c->reported_drops = drops;
      send_text(*c, status_json(StatusLevel::kWarning, m.str()));
    }
  }
}

void Bridge::Impl::send_text(Client& c, const std::string& text) {
  // a client that does not read gets no more text either: its socket buffer stays bounded
  if (ws->buffered(c.id) >= kSocketWatermark) return;
  ws->send(c.id, text.data(), text.size(), true);
}

void Bridge::Impl::on_open(ClientId id, const std::string& remote) {
  auto c = std::make_unique<Client>();
  c->id = id;
  c->queue = std::make_unique<ClientQueue>(options.queue_bytes, bulk_channels);
  std::lock_guard<std::mutex> l(mutex);
  c->counts.id = next_client_id++;
  c->counts.remote = remote;
  ++clients_total;
  std::ostringstream session;
  session << "teleop-" << options.port << "-" << c->counts.id;
  const std::string info = server_info_json("teleop_bridge", session.str());
  ws->send(id, info.data(), info.size(), true);
  ws->send(id, advertise.data(), advertise.size(), true);
  clients.emplace(id, std::move(c));
}

void Bridge::Impl::on_close(ClientId id) {
  std::lock_guard<std::mutex> l(mutex);
  auto it = clients.find(id);
  if (it == clients.end()) return;
  auto& c = *it->second;
  const auto& q = c.queue->counts();
  c.counts.sent = q.sent;
  c.counts.dropped_bulk = q.dropped_bulk;
  c.counts.dropped_kept = q.dropped_kept;
  c.counts.too_large = q.too_large;
  c.counts.queued_bytes = 0;
  c.counts.connected = false;
  departed.push_back(c.counts);
  clients.erase(it);
}

void Bridge::Impl::on_message(ClientId id, bool text, const std::string& payload) {
  std::lock_guard<std::mutex> l(mutex);
  auto it = clients.find(id);
  if (it == clients.end()) return;
  Client& c = *it->second;
  if (!text) {
    ++c.counts.bad_requests;
    send_text(c, status_json(StatusLevel::kError,
                             "teleop_bridge is read-only: binary client messages (client publish, "
                             "service calls) are not supported; ignored"));
    return;
  }
  handle_request(c, payload);
}

void Bridge::Impl::handle_request(Client& c, const std::string& text) {
  const ClientRequest r = parse_client_request(text);
  switch (r.kind) {
    case ClientRequest::Kind::kSubscribe:
      subscribe(c, r.subscribe);
      return;
    case ClientRequest::Kind::kUnsubscribe:
      for (const auto id : r.unsubscribe) {
        std::erase_if(c.subs, [id](const Subscription& s) { return s.id == id; });
      }
      return;
    case ClientRequest::Kind::kUnsupported:
      ++c.counts.bad_requests;
      send_text(c, status_json(StatusLevel::kWarning, "teleop_bridge is read-only: op '" + r.op +
                                                          "' is not supported (allowed: subscribe, "
                                                          "unsubscribe); ignored"));
      return;
    case ClientRequest::Kind::kInvalid:
      ++c.counts.bad_requests;
      send_text(c, status_json(StatusLevel::kError, "teleop_bridge: " + r.error + "; ignored"));
      return;
  }
}

void Bridge::Impl::subscribe(Client& c, const std::vector<Subscription>& subs) {
  for (const auto& s : subs) {
    std::string why;
    if (s.channel_id < 1 || s.channel_id > topics.size()) {
      why = "channelId " + std::to_string(s.channel_id) + " is not advertised (allowed: 1-" +
            std::to_string(topics.size()) + ")";
    }
    for (const auto& o : c.subs) {
      if (o.id == s.id) why = "subscription id " + std::to_string(s.id) + " is already in use";
    }
    if (!why.empty() || c.subs.size() >= 4 * topics.size()) {
      if (why.empty()) why = "too many subscriptions";
      ++c.counts.bad_requests;
      send_text(c, status_json(StatusLevel::kError, "teleop_bridge: subscribe: " + why));
      continue;
    }
    c.subs.push_back(s);
    // a latched topic: the samples kept go to the late subscriber at once
    const Topic& t = *topics[s.channel_id - 1];
    // the scene and transforms are not kept: the next take (10 ms) builds them fresh for it
    if (t.derived != Derived::kNone) derived_now.store(true);
    std::uint8_t head[kMessageDataHeader];
    for (const auto& k : t.kept) {
      message_data_header(head, s.id, k.receive_ns);
      c.queue->push(FrameClass::kKept, 0, head, k.bytes);
    }
  }
  request_flush();
}

BridgeCounts Bridge::counts() const {
  std::lock_guard<std::mutex> l(impl_->mutex);
  BridgeCounts out;
  out.samples = impl_->samples;
  out.clients_total = impl_->clients_total;
  out.clients_refused = impl_->clients_refused;
  out.rejected = impl_->rejected.load();
  out.unauthorized = impl_->unauthorized;
  out.pages = impl_->pages;
  for (const auto& [id, c] : impl_->clients) {
    ClientCounts cc = c->counts;
    const auto& q = c->queue->counts();
    cc.sent = q.sent;
    cc.dropped_bulk = q.dropped_bulk;
    cc.dropped_kept = q.dropped_kept;
    cc.too_large = q.too_large;
    cc.queued_bytes = c->queue->bytes();
    out.clients.push_back(cc);
  }
  out.clients.insert(out.clients.end(), impl_->departed.begin(), impl_->departed.end());
  return out;
}

void Bridge::stop() {
  if (impl_->stopping.exchange(true)) return;
  impl_->guard.set_trigger_value(true);
  if (impl_->dds_thread.joinable()) impl_->dds_thread.join();
  for (auto& t : impl_->topics) {
    if (t->reader) impl_->participant.subscriber()->delete_datareader(t->reader);
    t->reader = nullptr;
  }
  impl_->ws->stop();
}

std::string counts_line(const BridgeCounts& c) {
  std::ostringstream o;
  int connected = 0;
  for (const auto& k : c.clients) connected += k.connected ? 1 : 0;
  o << "clients " << connected << " (" << c.clients_total << " in all, " << c.clients_refused
    << " refused, " << c.unauthorized << " without the token), pages " << c.pages << ", samples "
    << c.samples << " (" << c.rejected << " not valid for the scene)";
  for (const auto& k : c.clients) {
    o << "; client " << k.id << " " << k.remote << (k.connected ? "" : " (gone)") << ": sent "
      << k.sent << ", dropped " << k.dropped_bulk << " mesh + " << k.dropped_kept
      << " other, queued " << k.queued_bytes << " bytes, bad requests " << k.bad_requests;
  }
  return o.str();
}

}  // namespace teleop::bridge
