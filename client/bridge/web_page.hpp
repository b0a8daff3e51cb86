#pragma once
// The bridge's own page (client/bridge/web/index.html, embedded at build time by CMake into
// web_page.cpp in the build tree): a 3-D view of bridge/scene in plain WebGL, plots of
// bridge/plot and the list of bridge/events, over the same port's WebSocket.
namespace teleop::bridge {

extern const char* const kBridgePage;

}  // namespace teleop::bridge
