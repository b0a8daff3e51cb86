#pragma once
// DDS domain ids owned by tests: each test that touches DDS uses its own, so tests running in
// parallel never hear each other. Add new ids here; never reuse one.
namespace teleop::test::domains {
inline constexpr int kRoundTrip = 41;
inline constexpr int kBadCommands = 42;
inline constexpr int kWatchdog = 43;
inline constexpr int kLinkLoss = 44;
inline constexpr int kObservers = 45;
inline constexpr int kDdsHelpers = 46;
inline constexpr int kExperiment3 = 47;
inline constexpr int kMeshTopics = 48;
inline constexpr int kMonitor = 49;
inline constexpr int kViewerToolScene = 80;     // teleop_viewer snapshot of the tool-only scene
inline constexpr int kViewerDefaultScene = 81;  // teleop_viewer snapshot of the default scene
inline constexpr int kViewerNoData = 82;        // teleop_viewer with no server: times out
inline constexpr int kViewerDrive = 83;         // viewer_drive_test: a session driven by the viewer
inline constexpr int kTuningRefused = 84;    // viewer_drive_test: a master without --accept-tuning
inline constexpr int kWaveSession = 60;      // passivity_test: wave-variables over DDS
inline constexpr int kTdpaSession = 61;      // passivity_test: tdpa over DDS
inline constexpr int kBadWaveCommands = 62;  // passivity_test: hostile wave commands
inline constexpr int kOtherVendor = 63;      // other_vendor_test: a Cyclone DDS reader
inline constexpr int kMultiHostLan = 64;     // multi_host_test, in its own namespaces
inline constexpr int kMultiHostWanTcp = 65;  // multi_host_test
inline constexpr int kMultiHostDiscovery = 66;        // multi_host_test
inline constexpr int kMultiHostLanUnicast = 69;       // multi_host_test
inline constexpr int kMultiHostDiscoveryBackup = 71;  // multi_host_test
inline constexpr int kNetworkFlags = 70;       // network_flags_test (exits before DDS starts)
inline constexpr int kMultiHostLauncher = 72;  // multi_host_test: deploy/teleop_launch.sh
inline constexpr int kRecordSession = 73;      // record_play_test: session under teleop_record
inline constexpr int kPlayback = 74;           // record_play_test: teleop_play to a subscriber
inline constexpr int kMonitorTui = 75;         // monitor_tui_test: teleop_monitor under tmux
inline constexpr int kMonitorJson = 76;        // monitor_tui_test: teleop_monitor --json
inline constexpr int kMonitorScene = 77;       // monitor_tui_test: the scene line of a server
inline constexpr int kHostileInputs = 78;  // tests/tools/hostile_inputs.sh (ctest hostile_inputs)
inline constexpr int kRecordMcap = 79;     // record_play_test: an MCAP session, a kill -9
inline constexpr int kNodeMcapCheck = 85;  // tests/node/run_mcap_check.sh (ctest node.*)
inline constexpr int kPlaybackMcap = 86;   // record_play_test: an MCAP file played back
inline constexpr int kBridgeSession = 87;  // bridge_test: a client of teleop_bridge
inline constexpr int kBridgeSlowClient = 88;  // bridge_test: a client that never reads
inline constexpr int kNodeBridgeCheck = 89;   // tests/node/run_bridge_check.sh (ctest node.*)
inline constexpr int kDriverSilence = 94;     // driver_silence_test: an external driver goes silent
inline constexpr int kSecureOutsiders = 105;  // security_test: no credentials / foreign CA
inline constexpr int kSecureObserver = 106;   // security_test: observer reads, cannot command
inline constexpr int kSecureSession = 107;    // security_test: server + master, secure
inline constexpr int kSecureBadFiles = 108;   // security_test: bad files (exits before DDS)
inline constexpr int kSecureStranger = 109;   // security_test: identity of another CA
// 104: tests/bench/record_kill.sh
// 110, 111: tests/bench/security_rtt.sh (plain, secure); 112: teleop_bench rtt in docs
inline constexpr int kMultiHostSecureLanUnicast = 113;  // multi_host_test, secure_lan_unicast
inline constexpr int kMultiHostSecureWanTcp = 114;      // multi_host_test, secure_wan_tcp_*
inline constexpr int kServerFaultVerdict = 130;         // server_health_test: a fault on the server
inline constexpr int kServerRestart = 131;              // server_health_test: kill -9 and restart
inline constexpr int kServerGainClamp = 226;            // server_health_test: K_ps clamped
inline constexpr int kFaultDelaySpike = 133;  // fault_suite_test: a 1 s delay spike mid-contact
inline constexpr int kFaultLossWindow = 134;  // fault_suite_test: 50 % loss for 1 s mid-contact
inline constexpr int kFaultNanFlood =
    135;  // fault_suite_test: NaN commands from a third participant
inline constexpr int kResimSession = 132;     // record_play_test: recorded, re-simulated, replayed
inline constexpr int kObserverRates = 115;    // observers_test: monitor on the 10 Hz topics
inline constexpr int kObserverSession = 116;  // observers_test: 8 observers, default scene
inline constexpr int kObserverLate = 117;     // observers_test: a late observer
inline constexpr int kRateLimitedUnit = 118;  // rate_limited_publisher_test: 118, 119, 120
// 121-124: reserved for observer tests
inline constexpr int kBadScenes = 101;          // bad_scene_test: refused scenes (exit before DDS)
inline constexpr int kSubstepScene = 102;       // bad_scene_test: a scene that sub-steps runs
inline constexpr int kMalformedCommands = 103;  // bad_scene_test: malformed command payloads
// kExperiment3 + 20 = 67: the unstable-loop test; + 21 = 68: the external device test
inline constexpr int kOwnerRefused = 140;      // ownership_test: a second master is refused
inline constexpr int kOwnerRelease = 141;      // ownership_test: a waiting master after a release
inline constexpr int kOwnerKilled = 142;       // ownership_test: the owner killed, taken over
inline constexpr int kOwnerRestart = 143;      // ownership_test: server restart mid-contact
inline constexpr int kRogueBaseline = 144;     // trust_test: the session without a rogue
inline constexpr int kRogueParticipant = 145;  // trust_test: forged states, stats and events
inline constexpr int kTcpLinkCut = 146;        // trust_test: wan_tcp, the master's link cut
inline constexpr int kAsyncWriterUnit = 147;   // async_writer_test: 147, 148
inline constexpr int kPythonRecording = 180;   // tests/python/test_teleop.py: a live session
                                               // recorded by teleop_record, read from Python
// 149: reserved for ownership tests; 150-159, 160-169: transparency and contact tests
// 170: smoke.bench-observers-live (tests/CMakeLists.txt: teleop_bench observers --live)
// 171: tests/bench/bridge_load.sh
// 173: tests/bench/tcp_link_cut.sh (in network namespaces of its own)
inline constexpr int kNodeBridgePage = 200;    // tests/node/run_page_check.sh: the page in Chromium
inline constexpr int kNodeBridgeAccess = 201;  // tests/node/run_access_check.sh: TLS and the token
// 202: tests/bench/bridge_clients.sh (1, 10, 50 clients against no bridge)
// 203: deploy/make_docs.sh (the bridge page's picture); 204-209: reserved for bridge tests
inline constexpr int kManyObservers = 190;       // many_observers_test: 100 observers find a server
inline constexpr int kOversizedUnit = 191;       // log_summary_test: oversized samples counted
inline constexpr int kObserverLimit = 192;       // observer_limit_test: the server counts observers
inline constexpr int kSecureShortLived = 194;    // security_test: make_security.sh --hours 2
inline constexpr int kParticipantRefused = 225;  // participant_test: a profile Fast DDS refuses
inline constexpr int kEventPublisherUnit = 227;  // event_publisher_test: an event round trip
// 195-199: reserved for network tests (196: the observers runs of docs/results.md)
// 215, 216, 217: deploy/make_docs.sh live, live-fifo, live-nice (the live sessions of
// docs/results.md, "Live session: the loops on real machines"); 218-219: reserved for them
// 60-99: reserved for more integration tests; 100+: benchmarks
}  // namespace teleop::test::domains
