#include "symb/io/dds/dds_participant.hpp"

#include <chrono>

#include <dds/dds.h>

namespace symb::io::dds {

std::string error_text(std::int32_t rc) { return std::string(dds_strretcode(rc)); }

std::string topic_part(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    if (c == '.' || c == '-') c = '_';
  return out;
}

kernel::Result<Participant> open_participant(std::uint32_t domain, kernel::Duration lease, std::string_view who) {
  if (domain > kMaxDomain)
    return kernel::Error{std::string(who) + ": domain " + std::to_string(domain) + " is above " +
                         std::to_string(kMaxDomain)};
  if (lease <= kernel::Duration{0}) return kernel::Error{std::string(who) + ": the liveliness lease must be positive"};
  const auto lease_ms = 3 * std::chrono::duration_cast<std::chrono::milliseconds>(lease).count();
  const std::string config = "<CycloneDDS><Domain><Discovery><LeaseDuration>" + std::to_string(lease_ms) +
                             "ms</LeaseDuration></Discovery></Domain></CycloneDDS>";
  Participant p;
  const dds_entity_t d = dds_create_domain(domain, config.c_str());
  if (d > 0) p.domain = d;
  const dds_entity_t e = dds_create_participant(domain, nullptr, nullptr);
  if (e < 0) {
    if (p.domain > 0) dds_delete(p.domain);
    return kernel::Error{std::string(who) + ": no participant on domain " + std::to_string(domain) + ": " +
                         error_text(e)};
  }
  p.participant = e;
  return p;
}

void close_participant(Participant& p) {
  if (p.participant > 0) dds_delete(p.participant);
  if (p.domain > 0) dds_delete(p.domain);
  p = {};
}

dds_qos* reliable_qos(kernel::Duration lease) {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(0));
  dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
  dds_qset_liveliness(qos, DDS_LIVELINESS_AUTOMATIC,
                      std::chrono::duration_cast<std::chrono::nanoseconds>(lease).count());
  return qos;
}

}  // namespace symb::io::dds
