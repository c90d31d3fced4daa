namespace vlab::lab {}
