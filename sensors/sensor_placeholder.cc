namespace vlab::sensors {}
