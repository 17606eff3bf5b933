# Source me: runs cairn on loopback only (no other network is touched) on a private DDS domain.
export CYCLONEDDS_URI="${CYCLONEDDS_URI:-<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><Peers><Peer address=\"127.0.0.1\"/></Peers><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>60</MaxAutoParticipantIndex></Discovery></Domain></CycloneDDS>}"
export CAIRN_DOMAIN_ID="${CAIRN_DOMAIN_ID:-$(( (RANDOM % 200) + 20 ))}"
_cairn_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="$_cairn_root/build/bin:$PATH"
# Other shells reach this one's nodes only on the same domain: say which (interactive shells only).
if [[ $- == *i* ]]; then
  echo "cairn: DDS domain $CAIRN_DOMAIN_ID (in another shell: export CAIRN_DOMAIN_ID=$CAIRN_DOMAIN_ID; source scripts/env.sh)" >&2
fi
