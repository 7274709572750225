// ecattool test harness (tests/startup/test_startup_ros2_driver.py): ethercat_driver_ros2's generic slave reads a slave
// file with its own code (generic_ec_slave.cpp from ../shared/consumers, built against yaml-cpp and IgH's ecrt.h,
// pluginlib stubbed), and this prints what it would configure: identity, SDO bytes, PDO entries, sync managers.
#include <cstdio>
#include "generic_ec_slave.cpp"

struct Probe : ethercat_generic_plugins::GenericEcSlave {
  void dump() {
    std::printf("identity %u %u %u\n", vendor_id_, product_id_, assign_activate_);
    for (auto & s : sdo_config) {
      uint8_t buf[8] = {0};
      s.buffer_write(buf);
      std::printf("sdo %u %u %s", s.index, s.sub_index, s.data_type.c_str());
      for (size_t k = 0; k < s.data_size(); k++) std::printf(" %02x", buf[k]);
      std::printf("\n");
    }
    for (auto * list : {&rpdos_, &tpdos_}) {
      for (auto & p : *list) {
        std::printf("pdo %s %u", list == &rpdos_ ? "rx" : "tx", p.index);
        for (unsigned k = 0; k < p.n_entries; k++)
          std::printf(" %u:%u:%u", p.entries[k].index, p.entries[k].subindex, p.entries[k].bit_length);
        std::printf("\n");
      }
    }
    for (auto & s : syncs_) {
      if (s.index == 0xff) break;
      std::printf("sync %u %d %u %d\n", s.index, (int)s.dir, s.n_pdos, (int)s.watchdog_mode);
    }
  }
};

int main(int argc, char ** argv) {
  Probe p;
  std::vector<double> state(64), command(64);
  try {
    if (!p.setupSlave({{"slave_config", argv[1]}}, &state, &command)) { std::printf("refused\n"); return 2; }
  } catch (const std::exception & e) { std::printf("exception %s\n", e.what()); return 3; }
  p.dump();
  return 0;
}
