// What every user of Cyclone DDS in Symbricator shares (the DDS bus, dds_bus.hpp; the frame
// streams of a split world, dds_frame_stream.hpp): a process's participant on a domain whose
// discovery lease is tied to the liveliness lease, the reliable keep-all QoS with automatic
// liveliness, topic names after ROS 2's conventions, and DDS's error texts. One place, so that
// both kinds of peer notice a vanished process alike.
//
// This header includes no DDS header (the installed headers promise no DDS to their users):
// DDS's entities and return codes are 32-bit integers (dds_entity_t, dds_return_t) and its QoS an
// opaque struct, which is how they appear here.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

struct dds_qos;  // Cyclone's dds_qos_t

namespace symb::io::dds {

inline constexpr std::uint32_t kMaxDomain = 232;  // Cyclone's highest domain id with the default ports

// DDS's text for a return code ("Timeout", "Precondition not met", ...).
std::string error_text(std::int32_t rc);

// DDS topic names take letters, digits, '_' and '/': a name's '.' and '-' become '_'.
std::string topic_part(std::string_view s);

// A participant on `domain`. The first participant of a process on a domain makes the domain with a
// participant lease of three liveliness leases (Cyclone's default is 10 s): a killed peer's
// writers then miss their liveliness lease first (counted lost) before its participant expires and
// takes them away, and a writer to a dead reader does not fill its history for long. The domain is
// deleted with close(), taking any other participant of the process on it along.
struct Participant {
  std::int32_t participant = 0;
  std::int32_t domain = 0;  // made by this participant (else another one of the process made it)
};
// `who` names the caller in errors ("dds bus", "split world").
kernel::Result<Participant> open_participant(std::uint32_t domain, kernel::Duration lease, std::string_view who);
void close_participant(Participant& p);

// Reliable, keep-all, automatic liveliness with `lease`; dds_delete_qos() it after use.
dds_qos* reliable_qos(kernel::Duration lease);

}  // namespace symb::io::dds
