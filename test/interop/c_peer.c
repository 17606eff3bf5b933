/* A plain C DDS program, compiled with idlc from cairn's msgs/idl and linked only against libddsc: the
 * interoperability check of cairn's type support. It reads sensor_msgs/LaserScan on rt/interop/scan_in,
 * and writes each scan back on rt/interop/scan_out with frame_id suffixed "_c" and every range doubled.
 * Usage: c_peer <domain id> <number of scans> */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dds/dds.h"
#include "sensor_msgs/msg/LaserScan.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: c_peer <domain> <count>\n");
    return 2;
  }
  const dds_domainid_t domain = (dds_domainid_t)atoi(argv[1]);
  const int want = atoi(argv[2]);
  dds_entity_t pp = dds_create_participant(domain, NULL, NULL);
  if (pp < 0) {
    fprintf(stderr, "c_peer: participant: %s\n", dds_strretcode(pp));
    return 1;
  }
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 10);
  dds_entity_t tin = dds_create_topic(pp, &sensor_msgs_msg_dds__LaserScan__desc, "rt/interop/scan_in", NULL, NULL);
  dds_entity_t tout = dds_create_topic(pp, &sensor_msgs_msg_dds__LaserScan__desc, "rt/interop/scan_out", NULL, NULL);
  dds_entity_t rd = dds_create_reader(pp, tin, qos, NULL);
  dds_entity_t wr = dds_create_writer(pp, tout, qos, NULL);
  dds_delete_qos(qos);
  if (tin < 0 || tout < 0 || rd < 0 || wr < 0) {
    fprintf(stderr, "c_peer: cannot create entities\n");
    return 1;
  }
  int done = 0;
  for (int iter = 0; iter < 3000 && done < want; ++iter) { /* at most ~30 s */
    void* samples[1] = {NULL};
    dds_sample_info_t info;
    int n = dds_take(rd, samples, &info, 1, 1);
    if (n <= 0) {
      dds_sleepfor(DDS_MSECS(10));
      continue;
    }
    if (info.valid_data) {
      const sensor_msgs_msg_dds__LaserScan_* in = samples[0];
      sensor_msgs_msg_dds__LaserScan_ out = *in; /* shallow: reuses the loaned buffers except what we change */
      char frame[256];
      snprintf(frame, sizeof frame, "%s_c", in->header.frame_id);
      out.header.frame_id = frame;
      float* ranges = malloc(sizeof(float) * (in->ranges._length ? in->ranges._length : 1));
      for (uint32_t i = 0; i < in->ranges._length; ++i) ranges[i] = 2.0f * in->ranges._buffer[i];
      out.ranges._buffer = ranges;
      out.ranges._release = false;
      dds_write(wr, &out);
      free(ranges);
      ++done;
    }
    dds_return_loan(rd, samples, n);
  }
  dds_sleepfor(DDS_MSECS(500)); /* let the reliable writer deliver before the participant goes */
  dds_delete(pp);
  return done == want ? 0 : 3;
}
